"""Exports: :mod:`.coefficients` (fit coefficients, PX4 and ArduPilot parameters) and :mod:`.noise`
(IEEE 952 terms in SI, Kalibr/OpenVINS ``imu.yaml``). Nothing is imported here.
"""

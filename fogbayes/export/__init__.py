"""Exports: numbers in the forms filters and firmware take.

* :mod:`.coefficients` -- the coefficient document of a fit (scaled basis, covariance, raw
  coefficients with intervals) and PX4 thermal-compensation parameters;
* :mod:`.noise`        -- IEEE 952 noise terms in SI units, Kalibr/OpenVINS ``imu.yaml``.

Nothing is imported here.
"""

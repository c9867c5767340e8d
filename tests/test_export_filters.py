"""`fogbayes export`: Kalibr/OpenVINS imu.yaml, IEEE 952 JSON, ArduPilot INS_TCAL, PX4 TC_G.

References are independent of the code under test: unit conversions computed by hand here,
the truth of a simulated white-rate record, and ArduPilot's correction written out from
AP_InertialSensor_tempcal.cpp (correct_sensor / polynomial_eval).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml

from fogbayes.cli import main
from fogbayes.data import Recording, save
from fogbayes.export.coefficients import DEG_H_TO_RAD_S, ExportError, ardupilot_gyro_parameters
from fogbayes.models.polynomial import evaluate
from fogbayes.thermal.model import ThermalSpec, bias_t_spec, thermal_basis


@pytest.fixture(scope="module")
def adev_doc(tmp_path_factory):
    """Allan document of 2 h of white rate noise at 10 Hz with N = 0.01 deg/sqrt(h)."""
    folder = tmp_path_factory.mktemp("export")
    fs, n_true = 10.0, 0.01
    sigma = 60.0 * n_true * math.sqrt(fs)  # deg/h per sample: ADEV(tau0) = 60 N / sqrt(tau0 s)
    y = np.random.default_rng(5).normal(scale=sigma, size=72_000)
    rec = Recording(time=np.arange(y.size) / fs, output=y, unit="deg/h")
    save(rec, folder / "static.npz")
    out = folder / "adev.json"
    assert main(["-q", "allan", str(folder / "static.npz"), "--json", str(out)]) == 0
    return out, n_true


def _export(args, capsys):
    code = main(["-q", "export", *args, "--out", "-"])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def test_kalibr_noise_density_is_n_in_rad_s_sqrt_hz(adev_doc, capsys):
    path, n_true = adev_doc
    doc = json.loads(path.read_text())
    code, out, err = _export([str(path), "--format", "kalibr"], capsys)
    assert code == 0, err
    y = yaml.safe_load(out)
    n = doc["fit"]["terms"]["N"]
    # by hand: 1 deg/sqrt(h) = (pi/180) rad / sqrt(3600 s) = (pi/180)/60 rad/s/sqrt(Hz)
    assert y["gyroscope_noise_density"] == pytest.approx(n["value"] * math.pi / 180 / 60,
                                                         rel=1e-8)
    assert y["gyroscope_random_walk"] == pytest.approx(
        doc["fit"]["terms"]["K"]["value"] * math.pi / 180 / 3600 / 60, rel=1e-8)
    assert y["update_rate"] == 10 and y["rostopic"] == "/imu0"
    # and against the simulation's truth (72 000 samples: N to about 1 %)
    assert y["gyroscope_noise_density"] == pytest.approx(n_true * math.pi / 180 / 60, rel=0.03)
    assert "accelerometer" not in "".join(k for k in y)  # gyro only, said in a comment
    assert "accelerometer keys are not written" in out


def test_kalibr_quantile_writes_the_interval_end_and_refuses_others(adev_doc, capsys):
    path, _ = adev_doc
    doc = json.loads(path.read_text())
    code, out, _ = _export([str(path), "--format", "kalibr", "--quantile", "0.95"], capsys)
    assert code == 0 and "quantile 0.95" in out
    y = yaml.safe_load(out)
    assert y["gyroscope_noise_density"] == pytest.approx(
        doc["fit"]["terms"]["N"]["high"] * math.pi / 180 / 60, rel=1e-8)
    code, out, err = _export([str(path), "--format", "kalibr", "--quantile", "0.3"], capsys)
    assert code == 2 and "quantile 0.3 is not in the document" in err and "Traceback" not in err


def test_ieee952_document_si_and_discrete(adev_doc, capsys):
    path, _ = adev_doc
    code, out, _ = _export([str(path), "--format", "ieee952"], capsys)
    assert code == 0
    d = json.loads(out)
    n = d["terms"]["N"]
    assert n["si"]["value"] == pytest.approx(n["value"] * math.pi / 180 / 60, rel=1e-12)
    # discrete white noise per sample = continuous density * sqrt(fs)
    assert n["discrete"]["value"] == pytest.approx(n["si"]["value"] * math.sqrt(10.0), rel=1e-12)
    b = d["terms"]["B"]
    assert b["adev_floor"]["value"] == pytest.approx(b["value"] * 0.6643, rel=1e-4)
    assert d["terms"]["Q"]["si_unit"] == "rad" and d["ci"] == 0.9


def test_export_refuses_wrong_documents(adev_doc, capsys, tmp_path):
    path, _ = adev_doc
    code, _, err = _export([str(path), "--format", "ardupilot"], capsys)
    assert code == 2 and "bias-t" in err
    code, _, err = _export([str(path), "--format", "yaml"], capsys)
    assert code == 2 and "unknown export format" in err


def _ardupilot_correct(params, axis, T, T_cal, raw):
    """ArduPilot's correct_sensor, written out (rad/s): clamp, P(T-35), P(T_cal-35)."""
    p = "INS_TCAL1_"
    c = [params[f"{p}GYR{k}_{'XYZ'[axis]}"] for k in (1, 2, 3)]

    def poly(d):
        return (c[0] + (c[1] + c[2] * d) * d) * d * 1e-6

    T = np.clip(T, params[p + "TMIN"], params[p + "TMAX"])
    T_cal = min(max(T_cal, params[p + "TMIN"]), params[p + "TMAX"])
    return raw - poly(T - 35.0) + poly(T_cal - 35.0)


def test_ardupilot_parameters_reproduce_the_model_with_the_firmware_formula():
    T = np.linspace(-20.0, 60.0, 300)
    basis = thermal_basis(bias_t_spec(3), T[:, None])
    coef = np.array([-665.0, 45.0, 3.0, -0.8])  # deg/h
    axes = [(basis, coef), (basis, 0.5 * coef), (basis, -coef)]
    params = ardupilot_gyro_parameters(axes)
    assert (params["INS_TCAL1_TMIN"], params["INS_TCAL1_TMAX"]) == pytest.approx((-20.0, 60.0))
    T_cal = 25.0  # the boot-time gyro offset calibration removes the bias at T_cal
    for a, (b, c) in enumerate(axes):
        bias = np.asarray(evaluate(c, T[:, None], b)) * DEG_H_TO_RAD_S
        bias_cal = float(np.asarray(evaluate(c, np.array([[T_cal]]), b))[0]) * DEG_H_TO_RAD_S
        raw = bias - bias_cal  # what reaches the correction after the offset calibration
        corrected = _ardupilot_correct(params, a, T, T_cal, raw)
        assert np.max(np.abs(corrected)) < 1e-9 * np.max(np.abs(raw))
    thermal = thermal_basis(ThermalSpec(2, 1), np.column_stack([T, np.linspace(-1, 1, 300)]))
    with pytest.raises(ExportError, match="cubic in temperature only"):
        ardupilot_gyro_parameters([(thermal, np.zeros(thermal.n_terms))])


def test_ardupilot_and_px4_files_from_a_bias_t_fit(tmp_path, capsys):
    from fogbayes.simulate import simulate

    rec = tmp_path / "run.csv"
    save(simulate("thermal", seed=2, duration=1200.0, fs=1.0).recording, rec)
    fit = tmp_path / "fit.json"
    assert main(["-q", "fit", str(rec), "-m", "bias-t", "--json", str(fit)]) == 0
    out = tmp_path / "tcal.param"
    assert main(["-q", "export", str(fit), "-f", "ardupilot", "--index", "2",
                 "--out", str(out)]) == 0
    text = out.read_text()
    assert "INS_TCAL2_ENABLE,1" in text and "INS_TCAL2_GYR3_X," in text and "ACC1" not in text
    lo, hi = json.loads(fit.read_text())["params"]["valid_range"]["T"]
    assert f"INS_TCAL2_TMIN,{lo:.9g}" in text and f"INS_TCAL2_TMAX,{hi:.9g}" in text
    code, px4, _ = _export([str(fit), str(fit), "-f", "px4"], capsys)
    assert code == 0 and "TC_G0_X3_1" in px4 and "TC_G0_X0_2" not in px4


def test_kalibr_refuses_to_write_zero_noise(adev_doc, capsys, tmp_path):
    """A term the data do not resolve has an interval reaching 0: its lower end would tell
    the filter there is no such noise. Refused, naming the term."""
    path, _ = adev_doc
    doc = json.loads(path.read_text())
    doc["fit"]["terms"]["K"].update(low=0.0, present=False)
    edited = tmp_path / "edited.json"
    edited.write_text(json.dumps(doc))
    code, _, err = _export([str(edited), "--format", "kalibr", "--quantile", "0.05"], capsys)
    assert code == 2 and "K is 0 at quantile 0.05" in err
    code, out, _ = _export([str(edited), "--format", "kalibr"], capsys)
    assert code == 0 and "K not resolved by the data" in out
    code, _, err = _export([str(edited), "--format", "ieee952", "--quantile", "0.95"], capsys)
    assert code == 2 and "--quantile applies to --format kalibr" in err

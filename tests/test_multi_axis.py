"""Several axes in one run: `fogbayes allan LOG --axis all` (and `--column a,b,c`) writes
one document with one Allan document per axis, each equal to the single-axis run's; export,
report and plot take it; compensate refuses it by name."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import yaml

import _log_writers as W
from fogbayes.cli import main
from fogbayes.data import Recording, save
from fogbayes.data.axes_doc import AXES_SCHEMA

if os.environ.get("CI"):  # the test extra installs it: in CI a missing one is a failure
    import pyulog  # noqa: F401
else:
    pytest.importorskip("pyulog")


@pytest.fixture(scope="module")
def ulog(tmp_path_factory):
    path = tmp_path_factory.mktemp("axes") / "flight.ulg"
    W.write_ulog(path, {("sensor_gyro", 0): W.series(n=6000, fs=100.0)})
    return path


def _doc(path):
    return json.loads(path.read_text())


def test_axis_all_equals_three_single_axis_runs(ulog, tmp_path):
    out = tmp_path / "axes.json"
    assert main(["-q", "allan", str(ulog), "--axis", "all", "--json", str(out),
                 "--plot", str(tmp_path / "axes.png")]) == 0
    doc = _doc(out)
    assert doc["schema"] == AXES_SCHEMA and list(doc["axes"]) == ["x", "y", "z"]
    assert (tmp_path / "axes.png").stat().st_size > 0
    for a in ("y", "z"):
        one = tmp_path / f"{a}.json"
        assert main(["-q", "allan", str(ulog), "--axis", a, "--json", str(one)]) == 0
        single = _doc(one)
        assert doc["axes"][a]["adev"] == single["adev"]
        assert doc["axes"][a]["fit"]["terms"] == single["fit"]["terms"]
    # the three axes differ (the writer gives each its own noise size)
    n = [doc["axes"][a]["fit"]["terms"]["N"]["value"] for a in "xyz"]
    assert len(set(np.round(n, 12))) == 3


def test_axes_document_feeds_export_and_report_and_is_refused_by_compensate(ulog, tmp_path,
                                                                           capsys):
    out = tmp_path / "axes.json"
    assert main(["-q", "allan", str(ulog), "--axis", "x,y", "--json", str(out)]) == 0
    doc = _doc(out)
    assert list(doc["axes"]) == ["x", "y"]
    assert main(["-q", "export", str(out), "-f", "kalibr", "--out", str(tmp_path / "i.yaml")]) == 0
    y = yaml.safe_load((tmp_path / "i.yaml").read_text())
    n_si = [doc["axes"][a]["fit"]["terms"]["N"]["value"] * np.pi / 180 / 60 for a in "xy"]
    assert y["gyroscope_noise_density"] == pytest.approx(max(n_si), rel=1e-8)  # the largest
    assert main(["-q", "report", str(ulog), "--fit", str(out), "--out",
                 str(tmp_path / "r.html")]) == 0
    html = (tmp_path / "r.html").read_text()
    assert "axis x" in html and "axis y" in html
    capsys.readouterr()
    assert main(["-q", "compensate", str(ulog), "--params", str(out), "--out",
                 str(tmp_path / "c.csv")]) == 2
    assert "multi-axis" in capsys.readouterr().err


def test_columns_of_a_table_and_bad_axis_lists(tmp_path, capsys):
    rng = np.random.default_rng(2)
    rec = Recording(time=np.arange(4000) / 10.0, output=rng.normal(size=4000), unit="deg/h")
    path = tmp_path / "two.csv"
    save(rec, path)
    text = path.read_text().replace("time,output", "time,output,second")
    rows = text.splitlines()
    body = [r if r.startswith("#") or r.startswith("time") else f"{r},{rng.normal() * 3}"
            for r in rows]
    path.write_text("\n".join(body) + "\n")
    out = tmp_path / "cols.json"
    assert main(["-q", "allan", str(path), "--column", "output,second", "--json", str(out)]) == 0
    doc = _doc(out)
    n1, n2 = (doc["axes"][c]["fit"]["terms"]["N"]["value"] for c in ("output", "second"))
    assert n2 == pytest.approx(3 * n1, rel=0.1)  # white noise 3x larger
    assert main(["-q", "allan", str(path), "--column", "output,output", "--json", str(out)]) == 2
    assert main(["-q", "allan", str(path), "--axis", "x,w", "--json", str(out)]) == 2


def test_fit_axis_all_gives_firmware_parameters_for_three_axes(tmp_path):
    """One ULog, one command per step: bias-t per axis, then PX4 and ArduPilot files with
    x, y, z -- each axis's coefficients equal to its single-axis fit."""
    path = tmp_path / "ramp.ulg"
    W.write_ulog(path, {("sensor_gyro", 0): W.series(n=20000, fs=100.0)})
    out = tmp_path / "fit.json"
    assert main(["-q", "fit", str(path), "-m", "bias-t", "--axis", "all", "--json", str(out)]) == 0
    doc = _doc(out)
    assert doc["schema"] == AXES_SCHEMA and doc["model"] == "bias-t"
    one = tmp_path / "z.json"
    assert main(["-q", "fit", str(path), "-m", "bias-t", "--axis", "z", "--json", str(one)]) == 0
    assert doc["axes"]["z"]["params"]["coef"] == _doc(one)["params"]["coef"]
    px4 = tmp_path / "tc.params"
    assert main(["-q", "export", str(out), "-f", "px4", "--out", str(px4)]) == 0
    text = px4.read_text()
    assert all(f"TC_G0_X{k}_{a}\t" in text for k in range(4) for a in range(3))
    ap = tmp_path / "tcal.param"
    assert main(["-q", "export", str(out), "-f", "ardupilot", "--out", str(ap)]) == 0
    text = ap.read_text()
    assert all(f"INS_TCAL1_GYR{k}_{a}," in text for k in (1, 2, 3) for a in "XYZ")


def test_firmware_export_places_axes_by_name_not_position(tmp_path, capsys):
    """--axis y,x must not become x, y: the axes are placed by their names, and a set the
    firmware cannot take in x, y, z order (z alone, x and z) is refused."""
    path = tmp_path / "ramp.ulg"
    W.write_ulog(path, {("sensor_gyro", 0): W.series(n=20000, fs=100.0)})
    yx, xz = tmp_path / "yx.json", tmp_path / "xz.json"
    assert main(["-q", "fit", str(path), "-m", "bias-t", "--axis", "Y,x", "--json", str(yx)]) == 0
    assert list(_doc(yx)["axes"]) == ["y", "x"]
    x_only, y_only = tmp_path / "x.json", tmp_path / "y.json"
    for a, out in (("x", x_only), ("y", y_only)):
        assert main(["-q", "fit", str(path), "-m", "bias-t", "--axis", a, "--json", str(out)]) == 0
    by_name, by_order = tmp_path / "a.param", tmp_path / "b.param"
    assert main(["-q", "export", str(yx), "-f", "ardupilot", "--out", str(by_name)]) == 0
    assert main(["-q", "export", str(x_only), str(y_only), "-f", "ardupilot", "--out",
                 str(by_order)]) == 0
    assert by_name.read_text() == by_order.read_text()
    assert main(["-q", "fit", str(path), "-m", "bias-t", "--axis", "x,z", "--json", str(xz)]) == 0
    capsys.readouterr()
    assert main(["-q", "export", str(xz), "-f", "px4", "--out", str(tmp_path / "c.params")]) == 2
    assert "x, y, z" in capsys.readouterr().err
    assert main(["-q", "export", str(yx), "-f", "px4", "--index", "7",
                 "--out", str(tmp_path / "d.params")]) == 2


def test_logs_recorded_with_the_firmware_correction_on_are_flagged(tmp_path):
    """ArduPilot logs the rates after INS_TCAL and the board rotation; a fit of such a log
    carries warnings naming the parameter, and the exported file repeats them."""
    from fogbayes.data.logs import read_log

    ulg = tmp_path / "on.ulg"
    W.write_ulog(ulg, {("sensor_gyro", 0): W.series(n=500)}, params={"TC_G_ENABLE": 1})
    assert read_log(ulg).meta["px4_tc_g_enable"] == 1
    log = tmp_path / "on.bin"
    W.write_dataflash(log, {0: W.series(n=8000), 1: W.series(n=8000, seed=2)},
                      params={"AHRS_ORIENTATION": 4, "INS_TCAL1_ENABLE": 0,
                              "INS_TCAL2_ENABLE": 1})
    meta = read_log(log, instance=1).meta
    assert (meta["ardupilot_ahrs_orientation"], meta["ardupilot_tcal_enable"]) == (4, 1)
    info = tmp_path / "info.json"
    assert main(["-q", "info", str(log), "--instance", "1", "--axis", "z", "--json",
                 str(info)]) == 0
    doc = _doc(info)
    assert doc["log"]["log_instance"] == 1 and doc["log"]["axis"] == "z"
    assert any("INS_TCAL2_ENABLE = 1" in w for w in doc["warnings"])
    assert read_log(log).meta["ardupilot_tcal_enable"] == 0  # instance 0: INS_TCAL1
    fit = tmp_path / "fit.json"
    assert main(["-q", "fit", str(log), "-m", "bias-t", "--instance", "1", "--json",
                 str(fit)]) == 0
    warnings = _doc(fit)["warnings"]
    assert any("INS_TCAL2_ENABLE = 1" in w for w in warnings)
    assert any("AHRS_ORIENTATION = 4" in w for w in warnings)
    out = tmp_path / "tcal.param"
    assert main(["-q", "export", str(fit), "-f", "ardupilot", "--index", "2", "--out",
                 str(out)]) == 0
    assert "# warning:" in out.read_text() and "INS_TCAL2_ENABLE = 1" in out.read_text()

"""Recording validation and file round trips (CSV, Parquet, NPZ)."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes import errors
from fogbayes.data import Metadata, Recording, load, save


def _rec(n=50, k=2, rate=True):
    rng = np.random.default_rng(0)
    t = np.arange(n) * 0.1 + 1e5  # large offset: round trips must keep 17 digits
    return Recording(
        time=t,
        output=rng.normal(size=n) * 1e-3 + 12.345678901234567,
        unit="deg/s",
        temperatures=rng.normal(20, 5, size=(n, k)),
        input_rate=rng.normal(size=n) if rate else None,
        scale_factor=None,
        meta=Metadata(sensor_id="FOG-7", sample_rate=10.0),
    )


@pytest.mark.parametrize("ext", [".csv", ".parquet", ".npz"])
def test_round_trip_is_exact(tmp_path, ext):
    rec = _rec()
    back = load(save(rec, tmp_path / f"r{ext}"))
    np.testing.assert_array_equal(back.time, rec.time)
    np.testing.assert_array_equal(back.output, rec.output)
    np.testing.assert_array_equal(back.temperatures, rec.temperatures)
    np.testing.assert_array_equal(back.input_rate, rec.input_rate)
    assert back.temperature_names == ("temperature", "temperature_2")
    assert back.unit == "deg/s"
    assert back.meta.sensor_id == "FOG-7"
    assert back.meta.sample_rate == 10.0


def test_raw_unit_and_scale_factor_round_trip(tmp_path):
    rec = Recording(time=np.arange(4.0), output=[1.0, 2.0, 3.0, 4.0], unit="V", scale_factor=0.04)
    back = load(save(rec, tmp_path / "v.csv"))
    assert back.unit == "V" and back.scale_factor == 0.04
    # 1 V at 0.04 V/(deg/s) is 25 deg/s = 90 000 deg/h
    np.testing.assert_allclose(back.rate("deg/h")[0], 90_000.0, rtol=1e-15)


def test_rate_conversions_are_exact():
    rec = Recording(time=np.arange(3.0), output=[1.0, -2.0, 0.5], unit="rad/s")
    np.testing.assert_allclose(rec.rate("deg/s"), np.degrees([1.0, -2.0, 0.5]), rtol=1e-15)
    np.testing.assert_allclose(rec.rate("deg/h"), np.degrees([1.0, -2.0, 0.5]) * 3600, rtol=1e-15)


def test_raw_unit_without_scale_factor_is_an_error():
    rec = Recording(time=np.arange(3.0), output=np.ones(3), unit="Hz")
    with pytest.raises(errors.UnitError, match="scale factor"):
        rec.rate("deg/h")


def test_column_overrides_and_temperature_order(tmp_path):
    p = tmp_path / "odd.csv"
    p.write_text("t_s,gyro,temperature_3,temperature,temperature_2\n0,1,30,10,20\n1,2,31,11,21\n")
    rec = load(p, time="t_s", output="gyro")
    assert rec.temperature_names == ("temperature", "temperature_2", "temperature_3")
    np.testing.assert_array_equal(rec.temperatures[0], [10, 20, 30])
    rec2 = load(p, time="t_s", output="gyro", temperature=["temperature_3"])
    assert rec2.temperature_names == ("temperature_3",)


def test_gaps_are_reported_not_filled():
    t = np.r_[np.arange(10.0), np.arange(20.0, 30.0)]
    rec = Recording(time=t, output=np.zeros(20))
    s = rec.sampling()
    assert rec.n == 20  # nothing interpolated
    assert len(s.gaps) == 1 and s.gaps[0].index == 10 and s.gaps[0].duration == 11.0
    assert s.sample_rate == 1.0 and not s.irregular


def test_irregular_sampling_is_detected():
    t = np.cumsum(np.r_[0.0, np.full(20, 0.1) + np.linspace(-0.02, 0.02, 20)])
    assert Recording(time=t, output=np.zeros(21)).sampling().irregular


def test_recording_is_immutable():
    rec = _rec()
    with pytest.raises(ValueError):
        rec.output[0] = 1.0


@pytest.mark.parametrize("ext", ["csv", "npz", "parquet"])
def test_channels_under_any_name_survive_a_round_trip(tmp_path, ext):
    """save wrote 'T_case'/'T_fibre' columns that load (and --stream) then ignored: the
    channels were dropped without a word. The metadata now lists them."""
    from fogbayes.errors import MetadataError
    from fogbayes.stream import open_source

    T = np.column_stack([np.linspace(20, 30, 50), np.linspace(21, 31, 50)])
    rec = Recording(time=np.arange(50.0), output=np.zeros(50), temperatures=T,
              temperature_names=("T_case", "T_fibre"))
    path = save(rec, tmp_path / f"r.{ext}")
    back = load(path)
    assert back.temperature_names == ("T_case", "T_fibre")
    np.testing.assert_array_equal(back.temperatures, T)
    assert "temperatures" not in back.meta.extra
    if ext != "csv":
        assert open_source(path).temperature_names == ("T_case", "T_fibre")
    plain = save(Recording(time=np.arange(50.0), output=np.zeros(50), temperatures=T),
                 tmp_path / f"p.{ext}")
    assert load(plain).temperature_names == ("temperature", "temperature_2")
    if ext == "csv":  # a listed column that is gone: said, not skipped
        edited = path.read_text().replace(",T_fibre", ",T_other")  # the header, not the list
        (tmp_path / "edited.csv").write_text(edited)
        with pytest.raises(MetadataError, match="T_fibre"):
            load(tmp_path / "edited.csv")

"""``fogbayes compensate --stream``: the chunked path through the command line writes the
same rows as the in-memory command (the library equality is in test_stream.py)."""

import json

import numpy as np
import pandas as pd

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.simulate import simulate


def test_stream_flag_matches_the_in_memory_command(tmp_path, capsys):
    rec = simulate("paper004", seed=5, soak=600.0, ramp_rate=4.0).recording.slice(0, 3000)
    path = save(rec, tmp_path / "run.npz")
    fit = tmp_path / "fit.json"
    assert main(["-q", "fit", str(path), "--model", "bias-t", "--json", str(fit)]) == 0
    assert main(["-q", "compensate", str(path), "-p", str(fit), "-o",
                 str(tmp_path / "mem.csv")]) == 0
    capsys.readouterr()
    assert main(["compensate", str(path), "-p", str(fit), "-o", str(tmp_path / "s.parquet"),
                 "--stream", "--chunk-rows", "1024", "--json", "-", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)  # --json -: the summary and nothing else
    mem = pd.read_csv(tmp_path / "mem.csv")
    got = pd.read_parquet(tmp_path / "s.parquet")
    assert doc["rows"] == len(mem) == len(got) == rec.n
    # CSV keeps 17 significant digits: equal to the last bit of a float64
    np.testing.assert_array_equal(got["output"].to_numpy(), mem["output"].to_numpy())
    assert np.array_equal(got["outlier"].to_numpy(bool), mem["outlier"].to_numpy(bool))


def test_stream_refuses_a_csv_with_a_one_line_error(tmp_path, capsys):
    rec = simulate("paper004", seed=5, soak=600.0, ramp_rate=4.0).recording.slice(0, 1500)
    path = save(rec, tmp_path / "run.csv")
    fit = tmp_path / "fit.json"
    assert main(["-q", "fit", str(path), "--model", "bias-t", "--json", str(fit)]) == 0
    code = main(["-q", "compensate", str(path), "-p", str(fit), "-o", str(tmp_path / "o.npz"),
                 "--stream"])
    err = capsys.readouterr().err
    assert code == 2 and "run.csv" in err and "Traceback" not in err


def test_stream_takes_the_lab_units_the_in_memory_command_takes(tmp_path, capsys):
    rec = simulate("paper004", seed=5, soak=600.0, ramp_rate=4.0).recording.slice(0, 3000)
    fit = tmp_path / "fit.json"
    assert main(["-q", "fit", str(save(rec, tmp_path / "run.npz")), "--model", "bias-t",
                 "--json", str(fit)]) == 0
    lab = tmp_path / "lab.npz"  # time in ms, the temperature as raw words w = 100 (T + 20)
    np.savez(lab, time=1e3 * rec.time, output=rec.output,
             temperature=100.0 * (rec.temperatures[:, 0] + 20.0))
    units = ["--time-unit", "ms", "--temperature-scale", "0.01", "--temperature-offset", "-20"]
    assert main(["-q", "compensate", str(lab), "-p", str(fit), "-o", str(tmp_path / "mem.csv"),
                 "--output-unit", rec.unit, *units]) == 0
    assert main(["-q", "compensate", str(lab), "-p", str(fit), "-o",
                 str(tmp_path / "s.parquet"), "--output-unit", rec.unit, "--stream", "--chunk-rows",
                 "1024", *units]) == 0
    mem, got = pd.read_csv(tmp_path / "mem.csv"), pd.read_parquet(tmp_path / "s.parquet")
    assert len(got) == len(mem) == rec.n
    np.testing.assert_array_equal(got["output"].to_numpy(), mem["output"].to_numpy())
    np.testing.assert_allclose(got["time"].to_numpy(), rec.time, rtol=1e-15)
    capsys.readouterr()
    # without the units the raw words are refused, in one line naming the column
    code = main(["-q", "compensate", str(lab), "-p", str(fit), "-o", str(tmp_path / "x.parquet"),
                 "--output-unit", rec.unit, "--stream", "--time-unit", "ms"])
    err = capsys.readouterr().err
    assert code == 2 and "temperature" in err and "Traceback" not in err

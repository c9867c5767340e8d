"""``fogbayes demo`` runs the whole story and writes a report (short record for speed)."""

from __future__ import annotations

from fogbayes.cli import main


def test_demo_writes_report_and_thermal_beats_bias_t(tmp_path, capsys):
    # 1.5 h at 2 Hz keeps the test short; the full 6.3 h run is the command's default.
    assert main(["--quiet", "demo", "--out", str(tmp_path), "--duration", "5400", "--fs", "2"]) == 0
    out = capsys.readouterr().out
    assert "report:" in out and "bias stability" in out
    html = (tmp_path / "report.html").read_text()
    assert html.count("<img") >= 3 and "Allan deviation" in html
    assert (tmp_path / "demo_recording.csv").exists()
    # The simulated bias has a Shupe term, so the thermal model must compensate better.
    lines = {ln.split()[0]: ln for ln in out.splitlines() if ln.startswith("  ")}
    after = {m: float(lines[m].split("->")[1].split()[0]) for m in ("bias-t", "thermal")}
    assert after["thermal"] < after["bias-t"]

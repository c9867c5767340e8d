"""Numbers a report shows are what their labels say (issue 55): p-values at most 1, the
residual standard deviation's label, distinct colours per Allan term, loop panels that differ."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest


def test_two_looks_never_give_a_p_value_above_one(monkeypatch):
    """The better of two screening looks is Bonferroni-corrected, min(1, 2 p): a candidate
    with p = 0.9 under both noise models keeps log10 p <= 0 (it was log10 1.8 = 0.26)."""
    from fogbayes.loop.evidence import Screened
    from fogbayes.loop import core

    def screened(p):
        c = SimpleNamespace(effect="warm_up", covariates=())
        return Screened(c, None, None, 0.1, 1, math.log(p), 1.0, math.log(p))

    looks = iter([("wm1", [screened(0.9)]), ("wm2", [screened(0.95)])])
    monkeypatch.setattr(core.ev, "screen", lambda *a, **k: next(looks))
    monkeypatch.setattr(core, "with_reml", lambda ctx, fit, cache: fit)
    monkeypatch.setattr(core, "in_walk_mode", lambda fit: True)
    monkeypatch.setattr(core.nfit, "fit_noise", lambda *a, **k: None)
    fit = SimpleNamespace(noise=SimpleNamespace(spec=SimpleNamespace(_replace=lambda **k: None)),
                          X=None, _replace=lambda **k: SimpleNamespace())
    ctx = SimpleNamespace(y=None, grid=SimpleNamespace(mask=None, w=None))
    opts = SimpleNamespace(seed=0, n_sims=10)
    (s, wm), = core._screen_all(ctx, fit, [], opts, 0)
    assert s.log_p <= 0.0
    assert s.log_p == pytest.approx(0.0)  # min(1, 2 * 0.9) = 1
    assert wm == "wm1"  # the better look (0.9 < 0.95) is kept


def _lab(color) -> np.ndarray:
    """CIE L*a*b* (D65) of a matplotlib colour: the space where distance is seen difference."""
    from matplotlib.colors import to_rgb

    rgb = np.array(to_rgb(color))
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = m @ lin / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def _hue_deg(color) -> float:
    from colorsys import rgb_to_hsv

    from matplotlib.colors import to_rgb

    return 360.0 * rgb_to_hsv(*to_rgb(color))[0]


def _chromatic(color) -> bool:
    from colorsys import rgb_to_hsv

    from matplotlib.colors import to_rgb

    _, sat, val = rgb_to_hsv(*to_rgb(color))
    return sat >= 0.3 and val >= 0.25


def _allan_doc() -> dict:
    """A five-term Allan document with every term's curve (the fit's own formulas)."""
    tau = np.logspace(0, 3.5, 15)
    terms = {"Q": (0.3, "arcsec"), "N": (0.004, "deg/sqrt(h)"), "B": (0.004, "deg/h"),
             "K": (0.8, "deg/h^1.5"), "R": (8.0, "deg/h^2")}
    curves = {k: v[0] * tau ** p for (k, v), p in zip(terms.items(), (-1, -0.5, 0, 0.5, 1))}
    total = np.sqrt(sum(c ** 2 for c in curves.values()))
    return {"tau": tau.tolist(), "adev": total.tolist(), "adev_low": (0.9 * total).tolist(),
            "adev_high": (1.1 * total).tolist(), "ci": 0.9, "unit": "deg/h",
            "fit": {"method": "wls", "curves": {"tau": tau.tolist(), "total": total.tolist(),
                                                "terms": {k: c.tolist() for k, c in curves.items()}},
                    "terms": {k: {"value": v, "low": 0.5 * v, "high": 2 * v, "unit": u}
                              for k, (v, u) in terms.items()}}}


def test_allan_term_lines_have_distinct_colours():
    """Each coloured noise term's line has its own hue (>= 45 degrees apart) and a colour difference
    of at least 35 (CIE76) from every other term, the data grey and the fit line: the eye
    tells two colours apart from about ΔE 10 side by side; thin dashed lines need more."""
    import matplotlib.pyplot as plt

    from fogbayes.plot.allan import allan_figure

    fig = allan_figure(_allan_doc())
    ax = fig.axes[0]
    terms = {t: next(ln for ln in ax.get_lines() if f"{t} = " in ln.get_label()) for t in "QNBKR"}
    lines = {t: ln.get_color() for t, ln in terms.items()}
    fit = next(ln.get_color() for ln in ax.get_lines() if ln.get_label().startswith("fit"))
    data = ax.containers[0].lines[0].get_color()  # the ADEV points
    names = list(lines)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if _chromatic(lines[a]) and _chromatic(lines[b]):  # a grey has no hue
                dh = abs(_hue_deg(lines[a]) - _hue_deg(lines[b]))
                assert min(dh, 360 - dh) >= 45, (a, b, lines[a], lines[b])
            assert np.linalg.norm(_lab(lines[a]) - _lab(lines[b])) >= 35, (a, b)
        for other in (fit, data):
            assert np.linalg.norm(_lab(lines[a]) - _lab(other)) >= 35, (a, other)
    # and a dash pattern of its own, for print without colour
    assert len({str(ln._dash_pattern) for ln in terms.values()}) == 5
    plt.close(fig)


def test_allan_legend_leaves_the_plot_its_width():
    """The legend sits outside the axes, inside the figure, and the axes keep at least
    three quarters of the figure's width (it took half of it)."""
    import matplotlib.pyplot as plt

    from fogbayes.plot.allan import allan_figure

    fig = allan_figure(_allan_doc())
    fig.canvas.draw()
    ax = fig.axes[0]
    legend = ax.get_legend() or fig.legends[0]
    box, axbox, fbox = (legend.get_window_extent(), ax.get_window_extent(), fig.bbox)
    assert not box.overlaps(axbox)
    assert not box.overlaps(ax.xaxis.label.get_window_extent())
    assert not box.overlaps(ax.xaxis.get_tightbbox())  # nor the tick labels
    assert box.x0 >= fbox.x0 - 1 and box.x1 <= fbox.x1 + 1 and box.y0 >= fbox.y0 - 1
    assert axbox.width >= 0.75 * fbox.width
    plt.close(fig)


def test_residual_std_label_says_per_sample():
    """``residual_std`` is s = sqrt(weighted RSS / dof) with the block means weighted by
    their sample counts: the scatter of one sample. On 10 Hz white noise of sigma 0.5
    deg/h fitted on 1 s means it is 0.5 (block means scatter by 0.5 / sqrt(10) = 0.16),
    and the report's label says per sample."""
    from fogbayes.data import Metadata, Recording
    from fogbayes.render.html import render
    from fogbayes.render.labels import label
    from fogbayes.render.sections import model_section
    from fogbayes.thermal.workflow import fit_recording

    rng = np.random.default_rng(5)
    t = np.arange(36000) / 10.0
    temp = 20 + 10 * np.sin(2 * np.pi * t / 3600)
    rec = Recording(time=t, output=1.0 + 0.02 * temp + 0.5 * rng.standard_normal(t.size),
                    unit="deg/h", temperatures=temp[:, None], temperature_names=["temperature"],
                    meta=Metadata(sensor_id="white"))
    doc = fit_recording(rec, model="bias-t", orders="1")
    s = doc["fit"]["residual_std"]
    assert s == pytest.approx(0.5, rel=0.03)  # n = 3600 blocks: s.e. of s about 1.2 %
    text = label("residual_std")
    assert "per sample" in text and "(block means)" not in text
    page = render("fit", [model_section(doc)])
    assert "residual standard deviation per sample" in page


@pytest.fixture(scope="module")
def step_loop():
    """The loop on a 1 h record with a planted 2 deg/h step (one candidate, 20 null series)."""
    from fogbayes.loop import run_loop
    from fogbayes.loop.testbed import make_record

    tr = make_record("step", seed=1, duration=3600.0, fs=1.0, magnitude=2.0)
    res = run_loop(tr.recording, "bias-t", max_steps=1, n_sims=20, target_blocks=600,
                   effects=("step",))
    assert res.effects == ["step"]
    return tr, res


def test_a_step_second_panel_is_not_the_first_again(step_loop):
    """A step's driver is time: its second panel shows the residual after the step (whose
    spread is smaller: the step is gone), not the time panel drawn a second time."""
    import matplotlib.pyplot as plt

    from fogbayes.plot.loop import step_figure

    _, res = step_loop
    fig = step_figure(res, 0)
    a, b = fig.axes[:2]
    first = [np.asarray(ln.get_ydata(), float) for ln in a.get_lines()]
    second = [np.asarray(ln.get_ydata(), float) for ln in b.get_lines()]
    # the old second panel: the same two series as the first (before, model change)
    assert not (len(first) == len(second) and all(
        x.shape == y.shape and np.allclose(x, y) for x, y in zip(first, second)))
    after = second[1]
    assert np.std(after) < 0.8 * np.std(second[0])  # a 2 deg/h step dominated the before
    plt.close(fig)


def _step_phrase_numbers(res):
    """The planted step's size ± s.e. and time as the loop fitted them (deg/h, s)."""
    d = res.steps[0].detail
    return d["size_deg_h"]["value"], d["size_deg_h"]["stderr"], d["time_from_start_s"]


def test_loop_verdict_states_the_step_size_time_and_units(step_loop):
    """The headline verdict names the step's size ± s.e. in deg/h and its time (it said
    "added step (time)"); the fitted size lies within 5 s.e. of the planted one."""
    from fogbayes.render.effects import effect_phrase
    from fogbayes.render.html import fmt
    from fogbayes.render.loop import loop_headline
    from fogbayes.render.html import render

    tr, res = step_loop
    size, se, t_s = _step_phrase_numbers(res)
    true_size = tr.effect_params["size"]  # the simulator's planted step (deg/h)
    assert abs(size - true_size) < 5 * se
    page = render("loop", [loop_headline(res)])
    phrase = effect_phrase("step", res.steps[0].detail, res.steps[0].covariates)
    assert f"size {fmt(size, sig=4)} ± {fmt(se, sig=2)} deg/h" in phrase
    assert f"at t = {fmt(t_s, sig=4)} s" in phrase
    import html as H
    assert H.escape(f"The loop added {phrase}") in page


def test_loop_cli_result_line_states_the_effect(step_loop, tmp_path, monkeypatch, capsys):
    """`fogbayes loop` prints the added step with its size, time and units."""
    import fogbayes
    import fogbayes.loop
    from fogbayes.cli import main
    from fogbayes.render.html import fmt

    tr, res = step_loop
    csv = tmp_path / "step.csv"
    fogbayes.save(tr.recording, csv)
    monkeypatch.setattr(fogbayes.loop, "run_loop", lambda *a, **k: res)
    rc = main(["loop", str(csv), "-m", "bias-t", "--json", str(tmp_path / "l.json"),
               "--compensated", str(tmp_path / "l.csv")])
    err = capsys.readouterr().err
    assert rc == 0, err
    size, se, t_s = _step_phrase_numbers(res)
    line = next(ln for ln in err.splitlines() if ln.startswith("bias-t: added"))
    assert f"size {fmt(size, sig=4)} ± {fmt(se, sig=2)} deg/h" in line
    assert f"t = {fmt(t_s, sig=4)} s" in line


def test_report_of_a_loop_calibration_shows_the_loop_reports_numbers(step_loop, tmp_path):
    """`report --fit loop.json` states each term in physical units, the loop report's
    phrase (not only the coefficient on the centred, scaled column), and the base
    polynomial in raw form: evaluated at any temperature it equals the scaled form."""
    import json
    import html as H

    from fogbayes.render.calibration import physical_rows
    from fogbayes.render.effects import effect_phrase
    from fogbayes.workflow.report import build_report

    tr, res = step_loop
    doc = json.loads(json.dumps(res.to_json()))
    out = build_report(tr.recording, tmp_path / "r.html", fit=doc, allan=False)
    page = out.read_text()
    phrase = effect_phrase("step", res.steps[0].detail).split(": ", 1)[1]
    assert H.escape(phrase) in page
    # raw polynomial == scaled polynomial (intercept + tpoly) at -20, 20, 60 °C
    cal = doc["calibration"]
    base = physical_rows(cal)[0]
    assert base[0] == "base" and "origin 0 °C" in base[2]
    import re

    nums = [float(x) for x in re.findall(r"(?:constant|T\^\d) (-?[\d.]+(?:e-?\d+)?)",
                                           base[2].replace("×10⁻", "e-").translate(
                                               str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹", "0123456789")))]
    tp = next(t for t in cal["terms"] if t["kind"] == "tpoly")
    i_tp = sum(len(t["labels"]) for t in cal["terms"][:cal["terms"].index(tp)])
    c0 = cal["coefficients"][0]
    for T in (-20.0, 20.0, 60.0):
        z = (T - tp["params"]["centre"]) / tp["params"]["scale"]
        scaled = c0 + sum(cal["coefficients"][i_tp + j] * z ** k
                          for j, k in enumerate(tp["params"]["powers"]))
        raw = sum(a * T ** j for j, a in enumerate(nums))
        assert raw == pytest.approx(scaled, rel=2e-3, abs=2e-3)  # 4 shown digits

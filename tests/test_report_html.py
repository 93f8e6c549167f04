"""report.html: one valid, self-contained, responsive, printable file; one display convention."""

import html
import re
from html.parser import HTMLParser

import numpy as np
import pytest

from wheelsoil.model import DEFAULT_WHEEL, load_terrain
from wheelsoil.model.diagnosis import diagnose
from wheelsoil.model.fit import synthetic_data
from wheelsoil.model.report import (
    fmt,
    fmt_param,
    num,
    overlapping_groups,
    write_report,
)

SAND = load_terrain("sand")
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}
#: elements that may not appear inside <p> (HTML: a <p> ends at the next block element)
BLOCK = {"address", "article", "aside", "blockquote", "div", "dl", "fieldset", "figure", "footer", "form", "h1",
         "h2", "h3", "h4", "h5", "h6", "header", "hr", "main", "nav", "ol", "p", "pre", "section", "table", "ul"}


class StrictChecker(HTMLParser):
    """Strict well-formedness of an HTML5 document: every non-void element closed in order, no block
    element inside <p>, one <html>/<head>/<body>, a doctype, attributes quoted (html.parser accepts
    unquoted ones, so the source is checked separately)."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.counts, self.doctype = [], [], {}, False

    def handle_decl(self, decl):
        self.doctype = decl.lower() == "doctype html"

    def handle_starttag(self, tag, attrs):
        self.counts[tag] = self.counts.get(tag, 0) + 1
        if tag in BLOCK and "p" in self.stack:
            self.errors.append(f"<{tag}> inside <p> at {self.getpos()}")
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.counts[tag] = self.counts.get(tag, 0) + 1
        if tag not in VOID:
            self.errors.append(f"self-closed non-void <{tag}/> at {self.getpos()}")

    def handle_endtag(self, tag):
        if tag in VOID:
            self.errors.append(f"end tag of void <{tag}> at {self.getpos()}")
        elif not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> at {self.getpos()} but open: {self.stack[-3:]}")
            if tag in self.stack:
                while self.stack and self.stack.pop() != tag:
                    pass
        else:
            self.stack.pop()


def check_html(text: str) -> StrictChecker:
    """Parse ``text`` strictly; assert well-formed, self-contained, responsive and printable."""
    p = StrictChecker()
    p.feed(text)
    p.close()
    assert p.doctype, "no <!DOCTYPE html>"
    assert not p.errors, p.errors[:5]
    assert not p.stack, f"unclosed elements: {p.stack}"
    for tag in ("html", "head", "body", "title"):
        assert p.counts.get(tag) == 1, f"{tag}: {p.counts.get(tag)}"
    # self-contained: no scripts, no external resources
    assert "<script" not in text.lower()
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:)?//""", text, re.I)
    assert "@import" not in text and "url(" not in text
    # responsive and printable
    assert re.search(r"<meta name='viewport' content='width=device-width", text)
    assert "@media print" in text and "@media (max-width" in text
    assert "overflow-x:auto" in text
    # every table scrolls on a narrow screen
    assert text.count("<table>") == text.count("<div class='scroll'><table>")
    return p


def test_the_checker_catches_bad_html():
    bad = "<!DOCTYPE html><html><head><title>x</title></head><body><p><div>x</div></p><b><i>y</b></i></body></html>"
    p = StrictChecker()
    p.feed(bad)
    assert any("inside <p>" in e for e in p.errors) and any("</b>" in e for e in p.errors)


def _table(seed=0, model="lyasko", params=None, **kw):
    params = {"m1": 0.6, "m2": 0.03} if model == "lyasko" and params is None else params
    return synthetic_data(SAND, DEFAULT_WHEEL, model, params, kind="table", n_rows=50, load_n=13000.0, seed=seed, **kw)


@pytest.fixture(scope="module")
def table_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("rep")
    df = _table(6, model="vasilev", params={"H": 0.05}, noise_z_m=0.004)
    diag = diagnose(df, SAND, DEFAULT_WHEEL)
    rep = write_report(diag, out, terrain=SAND, wheel=DEFAULT_WHEEL, inputs=["x.csv"])
    return rep, out, diag


def test_html_is_valid_self_contained_and_embeds_every_figure(table_report):
    rep, out, _ = table_report
    text = (out / "report.html").read_text()
    check_html(text)
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert text.count("data:image/png;base64,") == len(pngs) == len(rep["figures"])


def test_display_convention_one_formatter():
    assert num(11234.0) == "11200" and num(43.52) == "43.5" and num(0.0012345) == "0.00123"
    assert num(9.698e-06) == "9.70e-6" and num(9.996) == "10.0" and num(None) == "n/a"
    assert fmt(0.0312, "length_mm") == "31.2 mm" and fmt(850.0, "pressure") == "0.850 kPa"
    assert fmt(np.radians(28.1), "angle") == "28.1 deg" and fmt(float("nan"), "force") == "n/a"
    assert fmt_param("phi", np.radians(25.0), np.radians(0.5)) == "25.0 ± 0.50 deg"
    assert fmt_param("k_eq", 2.5e6) == "2500 kN/m^(n+2)"
    assert fmt_param("n1", 0.2330, 0.0011) == "0.233 ± 0.0011"


def test_tables_show_coefficients_in_field_units_and_json_in_si(table_report):
    rep, out, diag = table_report
    text = (out / "report.html").read_text()
    # terrain table in kPa / deg / mm / kN: the numbers of the terrain, converted by the formatter
    t = rep["terrain"]
    assert rep["terrain"]["c_pa"] == pytest.approx(SAND.c) and rep["terrain"]["phi_rad"] == pytest.approx(SAND.phi)
    assert f"<td>{fmt(t['c_pa'], 'pressure', unit=False)}</td>" in text
    assert f"<td>{fmt(t['k_m'], 'length_mm', unit=False)}</td>" in text
    assert "K [mm]" in text and "c [kPa]" in text and "phi [deg]" in text
    # a fitted coefficient appears in display units; JSON keeps SI with the unit named
    v = rep["models"]["vasilev"]["parameters"]["H"]
    assert v["unit"] == "m" and v["value"] == pytest.approx(diag.fits["vasilev"].params["H"])
    assert fmt_param("H", v["value"], v["se"]) in html.unescape(text)
    # no raw Python float reprs or exponent-with-plus formats in the HTML body text
    body = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", text)
    assert not re.search(r"\d\.\d{6,}", body), re.search(r".{40}\d\.\d{6,}.{20}", body)
    assert "e+0" not in body


def test_metrics_are_defined_where_shown(table_report):
    rep, out, _ = table_report
    text = (out / "report.html").read_text()
    for term in ("M0", "R0", "R²", "CV R0", "2 ln(Z/Z_Wong)", "probability"):
        assert f"<dt>{term}</dt>" in text
    assert "paper section 1.3" in text
    assert set(rep["metric_definitions"]) >= {"M0_pct", "R0", "R2", "cv_R0", "bic", "evidence", "probability"}
    assert "not whether the prediction is the right size" in rep["metric_definitions"]["R2"]
    # the evidence column is what the probabilities come from (the BIC column it replaced could rank Wong first
    # while the probabilities gave it 0): among the slip-sinkage forms, one prior weight, the same order
    forms = [k for k in ("vasilev", "lyasko", "ding") if rep["models"][k].get("log_evidence") is not None
             and rep["models"][k].get("probability")]
    assert len(forms) >= 2
    assert sorted(forms, key=lambda k: rep["models"][k]["log_evidence"]) == \
        sorted(forms, key=lambda k: rep["models"][k]["probability"])


def test_per_channel_table_and_reason_when_worse_than_wong(table_report):
    rep, out, _ = table_report
    text = (out / "report.html").read_text()
    assert "Per channel: in sample and out of sample" in text
    w = rep["models"]["wong"]["per_channel"]
    for k, m in rep["models"].items():
        if not m.get("per_channel") or k == "wong":
            continue
        for c in rep["channels"]:
            sfx = {"drawbar_pull_n": "n", "torque_nm": "nm", "sinkage_m": "m"}[c]
            worse = m["per_channel"][c][f"R0_{sfx}"] > 1.001 * w[c][f"R0_{sfx}"]
            listed = (m.get("worse_than_wong") or {}).get(c, {}).get("in_sample", False)
            assert worse == listed, (k, c)
            if listed:
                assert m["worse_than_wong"][c]["reason"] in html.unescape(text)


def test_overlapping_curves_are_detected_numerically():
    x = np.linspace(0, 1, 50)
    groups = overlapping_groups({"a": x, "b": x + 1e-6, "c": 2 * x, "d": x * (1 + 1e-4)})
    assert groups == [["a", "b", "d"], ["c"]]
    assert overlapping_groups({"a": x, "c": x + 0.1}) == [["a"], ["c"]]


def test_sinkage_figure_says_which_curves_overlap(table_report):
    rep, out, diag = table_report
    # Wong and terrain mismatch share the static sinkage (K and phi do not change z)
    if "terrain_mismatch" in diag.fits:
        notes = rep["figure_notes"].get("sinkage_vs_slip.png", [])
        assert any("Wong" in n and "terrain mismatch" in n and "overlap" in n for n in notes)
        assert "overlap" in (out / "report.html").read_text()


def _signals(seed, t0_excluded=None):
    """A processed-recording-like signals DataFrame (columns of process_recording) from the model."""
    df = synthetic_data(SAND, DEFAULT_WHEEL, "ding", {"n1": 0.3}, kind="timeseries", duration_s=40.0,
                        load_n=13000.0, seed=seed)
    r = DEFAULT_WHEEL.radius
    df["speed_mps"] = 2.0
    with np.errstate(divide="ignore"):
        df["omega_radps"] = np.where(df["slip"] < 1, 2.0 / (r * (1 - df["slip"].clip(upper=0.99))), np.nan)
    df["phase"] = np.where(df["cycle"] >= 0, "accel", "brake")
    df.loc[df.index[:150], "valid"] = False
    return df


def test_overview_per_input_marks_exactly_the_fitted_samples_and_processing_spans(tmp_path):
    import pandas as pd

    a, b = _signals(1), _signals(2)
    spans = [{"t0_s": 20.0, "t1_s": 24.0, "reason": "outlier timestamps"}]
    # the fit sees what processing kept: the excluded span is not valid
    b.loc[(b["t_s"] >= 20.0) & (b["t_s"] <= 24.0), "valid"] = False
    df = pd.concat([a.assign(run=0), b.assign(run=1)], ignore_index=True)
    diag = diagnose(df, SAND, DEFAULT_WHEEL, models=("ding",))
    details = [{"path": "a.mcap", "signals": a, "wheel_radius_m": DEFAULT_WHEEL.radius, "excluded": [],
                "quality": {"kind": "recording", "valid_share": float(a["valid"].mean())}},
               {"path": "b.mcap", "signals": b, "wheel_radius_m": DEFAULT_WHEEL.radius, "excluded": spans,
                "quality": {"kind": "recording", "valid_share": float(b["valid"].mean()), "excluded_spans": spans}}]
    rep = write_report(diag, tmp_path, terrain=SAND, wheel=DEFAULT_WHEEL, inputs=["a.mcap", "b.mcap"],
                       input_details=details)
    assert {"overview_0.png", "overview_1.png"} <= set(rep["figures"])
    q0, q1 = rep["data_quality"]
    assert q0["used_in_fit"] + q1["used_in_fit"] == rep["samples_used"]
    assert q1["excluded_samples"]["processing: outlier timestamps"] == int(((b["t_s"] >= 20) & (b["t_s"] <= 24)).sum())
    assert q0["excluded_samples"]["marked invalid by processing"] == 150
    text = (tmp_path / "report.html").read_text()
    check_html(text)
    assert text.count("data:image/png;base64,") == len(rep["figures"])
    assert "20.0-24.0 s: outlier timestamps" in text


def test_flags_are_derived_from_the_fit_when_the_diagnosis_gives_none():
    from types import SimpleNamespace

    from wheelsoil.model.report import derived_flags

    res = SimpleNamespace(at_bound=("m2",), names=("m1", "m2"), params={"m1": 0.09, "m2": 0.0},
                          correlation=np.array([[1.0, -0.99995], [-0.99995, 1.0]]), condition_number=401.0)
    ok = SimpleNamespace(at_bound=(), names=("H",), params={"H": 0.01}, correlation=np.eye(1), condition_number=1.0)
    flags = derived_flags({"lyasko": SimpleNamespace(result=res, params=res.params),
                           "vasilev": SimpleNamespace(result=ok, params=ok.params)})
    kinds = [(f["model"], f["kind"], f["parameter"]) for f in flags]
    assert kinds == [("lyasko", "at_bound", "m2"), ("lyasko", "correlation", "m1,m2"),
                     ("lyasko", "ill_conditioned", None)]
    assert "-0.99995" in flags[1]["detail"] and "401" in flags[2]["detail"]


def test_data_quality_rows_say_unknown_and_damaged():
    from wheelsoil.model.report import _quality_rows

    q = {"kind": "recording", "duration_s": 240.0, "valid_share": 0.9, "imported": True, "rejected_frames": 3,
         "lost_frames": {"GPS": {"lost": None, "received": 10, "method": "no cycle time"},
                         "WFT": {"lost": 5, "received": 995, "method": "counter"}},
         "damaged_chunks": ["x.mcap: chunk at byte 4096 of 9000 fails its CRC check"],
         "processing_quality": {"damage": [{"frames_lost": 869}]}, "complete": True,
         "gnss_latency_s": 0.1, "gnss_latency_stderr_s": 0.001, "inertia": {"applied": True}}
    rows = dict(_quality_rows(q))
    assert rows["lost frames GPS"].startswith("unknown") and rows["lost frames WFT"].startswith("5 of 1000")
    assert rows["damaged chunks"].startswith("1 skipped, 869 frames lost") and "CRC" in rows["damaged chunks"]
    assert rows["rejected frames (import)"] == "3" and rows["GNSS latency found and removed"].startswith("100 ms")


def test_a_damaged_input_is_said_at_the_top(table_report, tmp_path):
    _, _, diag = table_report
    msg = "x.mcap: chunk at byte 4096 of 9000 fails its CRC check and is skipped; frames lost: 869"
    write_report(diag, tmp_path, terrain=SAND, wheel=DEFAULT_WHEEL, inputs=["x.mcap"],
                 input_details=[{"path": "x.mcap", "quality": {"kind": "recording", "damaged_chunks": [msg]}}])
    text = (tmp_path / "report.html").read_text()
    check_html(text)
    assert text.index("Damaged input.") < text.index("class='verdict'") and html.escape(msg, quote=True) in text


def test_the_glance_names_the_model_each_channels_error_belongs_to():
    """A channel's error on new data is the compared model's (the named one, else the channel's own): it was
    labelled with the channel's own model, so a named Lyasko's error read "(none)" on a channel whose own
    verdict is none, and a catch-all's error carried a rival's name."""
    from wheelsoil.model.report import _glance, _title

    d = {"channels": {
        "drawbar_pull_n": {"measured": True, "wong_cv_rmse": 1.16, "best_cv_rmse": 0.573, "model": None,
                           "compared_model": "lyasko", "effect": "none"},
        "torque_nm": {"measured": True, "wong_cv_rmse": 30.0, "best_cv_rmse": None, "model": None, "effect": "none"}}}
    text = html.unescape(_glance(d))
    assert f"0.573 N ({_title('lyasko')})" in text and "(none)" not in text
    assert "n/a (no model supported on this channel)" in text


def test_a_coefficient_whose_standard_error_exceeds_it_is_marked():
    """K = 2.83 +- 110 mm was shown as a fitted value with its flags column "ok": a value its own standard
    error cannot tell from zero is marked so."""
    from wheelsoil.model.report import _coefficients_section

    rep = {"models": {"terrain_K": {"status": "ok", "parameters": {
        "K": {"value": 0.00283, "se": 0.110, "flags": []}, "c": {"value": 900.0, "se": 50.0, "flags": []}}}},
        "flags": [], "diagnosis": {}}
    text = html.unescape("".join(_coefficients_section(rep)))
    assert text.count("not told from 0") == 1 and "K = " in text


def test_a_probable_effect_that_is_not_named_says_why_under_the_headline():
    """"Effect: none" over "terrain_mismatch 1.0" read as a contradiction: the glance says which effect is the
    most probable and why the rule does not name it; a named effect, or none probable, adds nothing."""
    from wheelsoil.model.diagnosis import WHY_UNEXPLAINED
    from wheelsoil.model.report import _glance

    none = html.unescape(_glance({"effect": "none", "effect_probabilities": {"none": 1e-59, "terrain_mismatch": 1.0}}))
    assert "Not named:</b> the most probable effect is a terrain mismatch (probability 1.0)" in none
    assert "no systematic error of relevant size" in none
    unx = html.unescape(_glance({"effect": "unexplained", "why": "equally_well",
                                 "effect_probabilities": {"stress_distribution": 0.9, "slip_sinkage": 0.1}}))
    assert "a different normal-stress distribution (probability 0.90)" in unx and WHY_UNEXPLAINED["equally_well"] in unx
    for d in ({"effect": "slip_sinkage", "effect_probabilities": {"slip_sinkage": 1.0}},
              {"effect": "none", "effect_probabilities": {"none": 0.7, "terrain_mismatch": 0.3}}):
        assert "Not named" not in _glance(d)


def test_the_glance_speaks_of_effects_in_words_and_says_what_a_probable_hypothesis_counts_for():
    """The glance listed "terrain_mismatch 1.0" and channel verdicts "slip_sinkage" (report.json's codes) while
    the text named Vasil'ev + terrain re-fitted as the most probable hypothesis (0.75): the words are used, and
    why that hypothesis's probability counts for another effect is said."""
    from wheelsoil.model.report import _glance

    d = {"effect": "unexplained", "why": "rival_more_evidence",
         "channels": {"drawbar_pull_n": {"measured": True, "effect": "slip_sinkage", "wong_cv_rmse": 908.0,
                                         "best_cv_rmse": 284.0, "compared_model": "vasilev"}},
         "effect_probabilities": {"terrain_mismatch": 1.0},
         "probabilities": {"vasilev+terrain": 0.75, "lyasko+terrain": 0.25},
         "models": {"vasilev+terrain": {"effect": "slip_sinkage"}, "lyasko+terrain": {"effect": "slip_sinkage"}}}
    text = html.unescape(_glance(d))
    assert "slip_sinkage" not in text and "terrain_mismatch" not in text
    assert "a terrain mismatch 1.0" in text and "<td>slip sinkage</td>" in text
    assert "(0.75), counts for a terrain mismatch: what it adds does not improve its predictions of new data" in text


def test_the_flags_and_the_per_channel_table_use_words_not_codes(tmp_path):
    """The flags table's kind column read "at_bound", "ill_conditioned", and the per-channel table's effect
    "terrain_mismatch"; report.json keeps the codes."""
    from wheelsoil.model.report import _coefficients_section

    rep = {"models": {"lyasko": {"status": "ok", "parameters": {"m2": {"value": 0.0, "se": 0.01, "flags": ["at_bound"]}}}},
           "flags": [{"model": "lyasko", "parameter": "m2", "kind": "at_bound", "detail": "m2 = 0 is on a bound"},
                     {"model": "lyasko", "parameter": None, "kind": "ill_conditioned", "detail": "condition 111"}],
           "diagnosis": {}}
    text = html.unescape("".join(_coefficients_section(rep)))
    flags_table = text[text.index("<h3>Flags</h3>"):text.index("<dl>")]
    assert "<td>at bound</td>" in flags_table and "<td>ill conditioned</td>" in flags_table
    assert "at_bound" not in flags_table and "ill_conditioned" not in flags_table


def test_structure_tests_are_told_in_words_with_the_p_the_verdict_used():
    """The summary named the tests by their keys ("drawbar_pull_n@x") with Holm-adjusted p-values while the
    structure statements quoted raw p-values against a Bonferroni level for the same tests; report.json now
    keeps p_holm, and both speak of "drawbar pull along the run"."""
    from wheelsoil.model.structure import structure_title
    from wheelsoil.model.report import structure_statements

    assert structure_title("drawbar_pull_n@x") == "drawbar pull along the run"
    assert structure_title("torque_nm") == "torque against slip"
    rep = {"diagnosis": {"thresholds": {"alpha": 0.01, "min_effect_sigma": 1.0, "min_effect_rel": 0.03},
                         "structure_tests": {"wong": {
                             "drawbar_pull_n@x": {"p": 0.001, "p_holm": 0.02, "effect_sigma": 3.0, "effect_rel": 0.1,
                                                  "effect_abs": 300.0, "channel": "drawbar_pull_n"}}}}}
    (st,) = structure_statements(rep)
    assert st["kind"] == "not_significant" and "Holm-adjusted p = 0.020 >= 0.010" in st["text"]
    assert st["text"].startswith("drawbar pull along the run")


def test_overview_plots_take_the_figure_width_and_its_legends_stay_inside(tmp_path, monkeypatch):
    """The exclusion strip's reasons were y tick labels: a long processing reason squeezed every plot into a
    third of the figure's width, and the first panel's legend (with the phase shading) ran off its right edge
    ("shad..."). Each reason is now written in full over its bar and the shading is said under the plots."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from wheelsoil.model import report

    sig = _signals(3)
    sig.loc[sig.index[400:600], "phase"] = "drive"
    sig.loc[sig.index[600:700], "phase"] = "standstill"
    long = "WFT: 235 samples lost (counter gap longer than 3 samples): left invalid, not interpolated"
    longer = "a processing reason far longer than one line of the strip can hold, " * 4
    saved = []

    def keep(fig, path, plt_):
        fig.canvas.draw()
        saved.append(fig)
        return path

    monkeypatch.setattr(report, "_save", keep)
    for spans in ([{"t0_s": 10.0, "t1_s": 12.0, "reason": long}],  # as in a real run (f9r1_12.asc)
                  [{"t0_s": 10.0, "t1_s": 12.0, "reason": long}, {"t0_s": 20.0, "t1_s": 21.0, "reason": longer}]):
        saved.clear()
        stats = report.overview_figure(sig, DEFAULT_WHEEL.radius, 0.05, spans, tmp_path / "overview.png", "title",
                                       plt)
        (fig,) = saved
        try:
            fbox, r = fig.bbox, fig.canvas.get_renderer()
            axes = fig.axes
            assert len(axes) == 6
            for ax in axes:
                assert ax.get_position().width >= 0.6, ax.get_position()
            assert fig.legends, "the phase shading is explained in a legend of the figure"
            legends = [ax.get_legend() for ax in axes if ax.get_legend() is not None] + list(fig.legends)
            for leg in legends:
                e = leg.get_window_extent(r)
                assert fbox.x0 - 1 <= e.x0 and e.x1 <= fbox.x1 + 1 and fbox.y0 - 1 <= e.y0 and e.y1 <= fbox.y1 + 1, e
            written = list(axes[5].texts) + list(axes[5].get_yticklabels()) + [ax.title for ax in axes]
            for t in written:  # the reasons (and titles) do not run off the figure
                if t is not None and t.get_text().strip():
                    e = t.get_window_extent(r)
                    assert fbox.x0 - 1 <= e.x0 and e.x1 <= fbox.x1 + 1, (t.get_text(), e)
            # every piece of information stays: each phase shown, each reason in full
            shading = " ".join(t.get_text() for leg in fig.legends for t in leg.get_texts())
            for ph in ("accelerate phase", "steady driving", "brake phase", "standstill"):
                assert ph in shading
            said = " ".join(" ".join(t.get_text().split()) for t in axes[5].texts)
            for reason in stats["excluded"]:
                assert " ".join(reason.split()) in said, reason
            assert f"processing: {long}" in stats["excluded"]
        finally:
            plt.close(fig)


def _leaves(x):
    if isinstance(x, dict):
        for v in x.values():
            yield from _leaves(v)
    elif isinstance(x, list):
        for v in x:
            yield from _leaves(v)
    else:
        yield x


def test_data_quality_rows_are_readable_not_python_structures():
    """The table printed "processing: latency {...}", the WFT ripple's coefficient lists, a tone wheel of
    62831853071.8 teeth and "rows read 27.0000": every item is a row of words, counts as integers."""
    from wheelsoil.model.report import _quality_rows

    q = {  # report.json data_quality[0] of a real run (f9r1_12.asc), lost frames and warnings shortened
        "input": "/tmp/f9r1_12.asc", "kind": "recording", "duration_s": 119.95, "rate_hz": 100.0, "cutoff_hz": 5.0,
        "wheel_radius_m": 0.455, "wheel_radius_source": "given", "valid_share": 0.8998749478949563,
        "lost_frames": {
            "RT_SB_GPS_Speed": {"lost": 104, "gaps": 3, "longest_gap_s": 3.250713, "received": 2290,
                                "method": "frames counted against the nominal cycle time 50 ms (vehicle "
                                          "configuration [signals.gnss_speed] cycle_time_s)"},
            "WFT_RL_Force": {"lost": 235, "gaps": 1, "longest_gap_s": 0.471983, "counter_jumps": 0,
                             "received": 59740, "method": "counter, period 2.00 ms"}},
        "imported": True, "rejected_frames": None, "import_record": None, "damaged_chunks": [], "complete": None,
        "kernel_rx_dropped": None,
        "gnss_fix": {"time_fixes_used": 2290, "time_fix_outliers": 0, "time_residual_rms_s": 0.0011846170757417753},
        "gnss_latency_s": 0.10699051123702037, "gnss_latency_stderr_s": 0.04066273815393397,
        "latency_reference": "slip-traction consistency of the measured wheel (T/(rW) a function of slip, no "
                             "hysteresis) and GNSS dV/dt against the measured Fx (vehicle dynamics)",
        "inertia": {"applied": True, "wheel_mass_kg": 68.0, "wheel_inertia_kgm2": 8.9,
                    "max_abs_force_n": 59.02079164530653, "max_abs_torque_nm": 16.674689837224367,
                    "method": "Dp = Fx + m_w dV/dt, T = My - I_w domega/dt", "source": "given"},
        "excluded_spans": [{"t0_s": 112.13131274800001, "t1_s": 112.603309467,
                            "reason": "WFT: 235 samples lost (counter gap longer than 3 samples): left invalid, "
                                      "not interpolated"}],
        "processing_quality": {
            "timestamps": {"outlier_frames": 0, "outliers_by_message": {}, "joined_parts": 0, "non_monotonic": {},
                           "clock_steps": [], "grid_rows": 11995, "span_s": 119.94744200000001},
            "wft_ripple": {"samples": 53334, "revolutions": 50.384283744635546,
                           "coef": {"fx": [-135.0179406044485, -319.17411850132, -72.97707764118508,
                                           127.66694558221502],
                                    "fz": [-265.51723880913516, 106.92505679177302, -30.268347458712775,
                                           -175.45014756885882],
                                    "my": [0.0, 0.0, 0.0, 0.0]},
                           "fx_1x_n": 346.5573000329975, "fx_2x_n": 147.05272134625665,
                           "fz_1x_n": 286.23831307976786, "fz_2x_n": 178.04192523059197,
                           "my_1x_nm": 26.90617826695468, "my_2x_nm": 10.558847641590326,
                           "removed": ["fx_1x", "fx_2x", "fz_1x", "fz_2x"]},
            "wheel_speed_lag": {"estimate_s": 0.010901159669639659, "stderr_s": 0.00024131590860687903,
                                "gain": 0.9996687188012723, "applied": True, "note": "",
                                "per_tooth": {"lag_s": 0.010901159669639659, "stderr_lag_s": 0.002536101503173289,
                                              "pitch_rad": 1e-10, "stderr_pitch_rad": 0.004513857116819448,
                                              "teeth": 62831853071.79586, "applied": False,
                                              "note": "pitch 1e-10 +- 0.0045 rad: not 3 standard errors above "
                                                      "zero (the delay does not grow as the wheel slows)"},
                                "fronts_shifted": True},
            "latency": {"estimate_s": 0.10699051123702037, "stderr_s": 0.04066273815393397,
                        "method": "traction+dynamics", "reliable": False,
                        "reasons": ["standard error 40.7 ms > 15 ms"], "fronts_driven": True,
                        "candidates": {
                            "traction": {"estimate_s": 0.09657884716984269, "stderr_s": 0.041203843801820024,
                                         "stderr_stat_s": 0.03837651292190032, "systematic_s": 0.015,
                                         "usable": True, "note": "", "n": 2025,
                                         "method": "slip-traction consistency of the measured wheel"},
                            "wheel_reference": {"estimate_s": None, "stderr_s": None, "stderr_stat_s": None,
                                                "systematic_s": 0.0, "usable": False,
                                                "note": "fewer than 10 GNSS samples overlap a usable reference "
                                                        "speed", "n": 0,
                                                "method": "GNSS V aligned with a wheel-speed reference r*omega"}},
                        "search_range_s": [-0.1, 0.5]},
            "lost_frames": {"WFT_RL_Force": 235, "RT_SB_GPS_Speed": 104},
            "lost_frames_known_total": 339, "lost_frames_unknown": []},
        "warnings": ["GNSS LATENCY UNRELIABLE: applied 107.0 +- 40.7 ms (standard error 40.7 ms > 15 ms); "
                     "ProcessResult.quality['latency']"],
        "samples": 11995, "used_in_fit": 8928,
    }
    rows = _quality_rows(q)
    free_text = sorted({x for x in _leaves(q) if isinstance(x, str)}, key=len, reverse=True)
    ints = {x for x in _leaves(q) if isinstance(x, int) and not isinstance(x, bool) and x >= 10}
    for label, value in rows:
        text = f"{label} {value}"
        for s in free_text:  # text quoted from processing may hold brackets ("[signals.gnss_speed]")
            text = text.replace(s, "")
        assert "{" not in text and "[" not in text and "}" not in text and "]" not in text, (label, value)
        for n in ints:
            assert not re.search(rf"(?<![\d.]){n}\.\d", value), (label, value)
    d = dict(rows)
    assert d["processing: GNSS latency"].startswith("107.0 ± 40.7 ms (traction+dynamics; unreliable: standard "
                                                    "error 40.7 ms > 15 ms)")
    assert "search range: -100 to 500 ms" in d["processing: GNSS latency"]
    cands = d["processing: GNSS latency candidates"]
    assert "traction: 96.6 ± 41.2 ms" in cands and "wheel_reference: none" in cands and "not usable" in cands
    ripple = d["processing: WFT ripple locked to the wheel angle"]
    assert "Fx: 1st order 347 N (taken out), 2nd order 147 N (taken out)" in ripple
    assert "My: 1st order 26.9 N m (left in), 2nd order 10.6 N m (left in)" in ripple
    assert "53334 samples" in ripple and "-135" not in ripple
    lag = d["processing: wheel-speed lag"]
    assert "estimate: 10.9 ± 0.24 ms" in lag and "tone wheel: none found" in lag and "62831853071" not in lag
    assert "grid rows: 11995" in d["processing: timestamps"] and "span: 120 s" in d["processing: timestamps"]
    assert d["processing: lost frames"] == "339 known in total"
    assert d["GNSS fix"] == "time fixes used: 2290; time fix outliers: 0; time residual rms: 1.18 ms"
    assert "wheel mass: 68.0 kg" in d["inertia compensation"]
    assert d["samples used in the fit"] == "8928 of 11995"
    assert dict(_quality_rows({"kind": "table", "rows": 27})) == {"rows read": "27"}
    # the second report's per-tooth delay: a real tone wheel is named by its teeth
    q["processing_quality"]["wheel_speed_lag"]["per_tooth"]["teeth"] = 47.25025511031723
    assert "tone wheel: about 47 teeth" in dict(_quality_rows(q))["processing: wheel-speed lag"]

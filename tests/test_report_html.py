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
    for term in ("M0", "R0", "R²", "CV R0", "BIC", "probability"):
        assert f"<dt>{term}</dt>" in text
    assert "paper section 1.3" in text
    assert set(rep["metric_definitions"]) >= {"M0_pct", "R0", "R2", "cv_R0", "bic", "probability"}
    assert "not whether the prediction is the right size" in rep["metric_definitions"]["R2"]


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
    assert "Not named:</b> the most probable effect is terrain_mismatch (probability 1.0)" in none
    assert "no systematic error of relevant size" in none
    unx = html.unescape(_glance({"effect": "unexplained", "why": "equally_well",
                                 "effect_probabilities": {"stress_distribution": 0.9, "slip_sinkage": 0.1}}))
    assert "stress_distribution (probability 0.90)" in unx and WHY_UNEXPLAINED["equally_well"] in unx
    for d in ({"effect": "slip_sinkage", "effect_probabilities": {"slip_sinkage": 1.0}},
              {"effect": "none", "effect_probabilities": {"none": 0.7, "terrain_mismatch": 0.3}}):
        assert "Not named" not in _glance(d)

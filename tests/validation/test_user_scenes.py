"""A user's scene files (``pcsuite report FILE.toml | DIR``) are untrusted input: checked completely at load (one
line naming the file, the key and the value, before anything runs), names safe as file names, every string
escaped in the page, nothing written outside --out."""
import json
import os
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from converters.errors import ParameterError
from validation.scenes import SCENE_DIR, Scene, load_scene, load_scenes, scenes_of

from validation.cli import main

def tree(root: Path) -> dict:
    """Everything under ``root``: relative path -> kind and content."""
    out = {}
    for path in sorted(root.rglob("*")):
        rel = path.relative_to(root).as_posix()
        out[rel] = ("link", os.readlink(path)) if path.is_symlink() else ("dir",) if path.is_dir() else (
            "file", path.read_bytes())
    return out


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err: str) -> str:
    assert err.endswith("\n") and err.count("\n") == 1 and err.startswith("pcsuite: error: "), err
    return err[len("pcsuite: error: "):-1]


#: A scene that runs in about a second without ngspice (the implicit sliding-mode relay, 2 ms).
FAST = """\
converter = "boost"
control = "smc-implicit"
[params]
Vin = 10
L = "1m"
C = "100u"
R = 40
Vref = 20
band = 0.05
[run]
t_end = 0.002
"""
NASTY = "x' onerror='alert(1)\" <script>alert(2)</script> & ../../etc/passwd <img src=x onerror=alert(3)>"


def _scene(tmp_path, body: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(body)
    return path


# --- C: names ----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("value", ["../../../../escaped", "x' onerror='alert(1)", "..", ".", "a/b", "", "-a", "a" * 65])
def test_a_scene_name_that_is_not_a_safe_file_name_is_refused_at_load(value, tmp_path):
    path = _scene(tmp_path, f"name = {json.dumps(value)}\n" + FAST)
    with pytest.raises(ParameterError, match=r"^scene s.toml: name must be 1-64 letters, digits, '.', '_' or '-', "
                                             r"starting with a letter or digit \(it becomes a file name\); got "
                                             + re.escape(repr(value)) + "$"):
        load_scene(path)


def test_a_file_name_that_is_not_safe_needs_a_name_key_and_suites_are_names_too(tmp_path):
    path = _scene(tmp_path, FAST, "my scene.toml")
    with pytest.raises(ParameterError, match=r"^scene my scene.toml: name \(by default the file's name; set name = "
                                             r"\"...\"\) must be 1-64 letters.*; got 'my scene'$"):
        load_scene(path)
    assert load_scene(_scene(tmp_path, 'name = "ok"\n' + FAST, "my scene.toml")).name == "ok"
    with pytest.raises(ParameterError, match=r"^scene s.toml: suites entry must be 1-64 letters.*; got '../x'$"):
        load_scene(_scene(tmp_path, 'suites = ["../x"]\n' + FAST))


def test_a_scene_that_would_write_outside_out_is_refused_before_anything_runs(tmp_path, monkeypatch, capsys):
    from validation import suite

    def ran(*args, **kwargs):
        raise AssertionError("the suite ran")
    monkeypatch.setattr(suite, "run_suite", ran)
    work = tmp_path / "a" / "b" / "c"
    work.mkdir(parents=True)
    _scene(work, 'name = "../../../../escaped"\n' + FAST, "evil.toml")
    monkeypatch.chdir(work)
    before = tree(tmp_path)
    code, out, err = cli(capsys, "report", "evil.toml", "--out", "out")
    assert code == 2 and out == ""
    assert one_line(err).startswith("scene evil.toml: name must be 1-64 letters") and "'../../../../escaped'" in err
    assert tree(tmp_path) == before and not list(tmp_path.parent.glob("escaped"))


def test_two_scenes_with_one_name_are_refused(tmp_path):
    a, b = _scene(tmp_path, 'name = "same"\n' + FAST, "a.toml"), _scene(tmp_path, 'name = "same"\n' + FAST, "b.toml")
    with pytest.raises(ParameterError, match=r"^scene b.toml: name 'same' is already the name of scene a.toml; scene "
                                             r"names must be unique$"):
        load_scenes([a, b])


# --- D: complete validation at load ------------------------------------------------------------------------------

BUCK = 'converter = "buck"\n'
BAD = [
    (BUCK + "[methods.lcp]\nh = 1e-3\n",
     r"scene s.toml [methods.lcp] h must be a positive number below the switching period (1e-05 s); got 0.001"),
    (BUCK + "[methods.lcp]\nh = -1e-9\n",
     r"scene s.toml [methods.lcp] h must be a positive number below the switching period (1e-05 s); got -1e-09"),
    (BUCK + "[methods.lcp]\nh = true\n", r"scene s.toml [methods.lcp] h must be a number; got True"),
    (BUCK + "[methods.lcp]\ntheta = 0.3\n", r"scene s.toml [methods.lcp] theta must be in [0.5, 1]; got 0.3"),
    (BUCK + "[methods.lcp]\ntheta = 2\n", r"scene s.toml [methods.lcp] theta must be in [0.5, 1]; got 2"),
    (BUCK + "[run]\nperiods = 5\nwindow = 10\n", r"scene s.toml [run] window must be in [1, periods = 5]; got 10"),
    (BUCK + "[run]\nperiods = 5\n", r"scene s.toml [run] window must be in [1, periods = 5]; got 10 (the default)"),
    (BUCK + "[run]\nperiods = true\n", r"scene s.toml [run] periods must be an integer in [1, 100000]; got True"),
    (BUCK + "[run]\nperiods = 2.5\n", r"scene s.toml [run] periods must be an integer in [1, 100000]; got 2.5"),
    (BUCK + "[run]\nwindow = 0\n", r"scene s.toml [run] window must be an integer in [1, 100000]; got 0"),
    (BUCK + "[run]\nstart = \"later\"\n", r"scene s.toml [run] start must be 'steady' or 'rest'; got 'later'"),
    (BUCK + "[run]\nt_end = 0.01\n",
     r"scene s.toml [run] t_end does not apply to a pwm scene; valid keys: start, periods, window"),
    (BUCK + "description = 5\n", r"scene s.toml: description must be a string; got 5"),
    (BUCK + "name = 5\n", r"scene s.toml: name must be a string; got 5"),
    ("converter = 5\n", r"scene s.toml: converter must be a string; got 5"),
    (BUCK + "control = [\"smc\"]\n", r"scene s.toml: control must be a string; got ['smc']"),
    (BUCK + "control = \"voltage-mode\"\n",
     r"scene s.toml: control must be one of pwm, smc, smc-implicit; got 'voltage-mode'"),
    (BUCK + "suites = \"default\"\n", r"scene s.toml: suites must be a list of names; got 'default'"),
    (BUCK + "[params]\nL = \"10u<script>\"\n", r"scene s.toml [params]: L"),
    (BUCK + "[params]\nD = true\n", r"scene s.toml [params]: D"),
    (BUCK + "[methods.spice]\nedge_fraction = 10\n",
     r"scene s.toml [methods.spice] edge_fraction (the gate's rise and fall time as a fraction of the switching "
     r"period) must be in [1e-09, 0.01]; got 10"),
    (BUCK + "[methods.spice]\ndiode_n = 1e-300\n",
     r"scene s.toml [methods.spice] diode_n (the diode's emission coefficient N) must be in [0.0001, 10]; got 1e-300"),
    (BUCK + "[methods.spice]\nreltol = 0.5\n",
     r"scene s.toml [methods.spice] reltol (ngspice RELTOL) must be in [1e-09, 0.1]; got 0.5"),
    (BUCK + "[methods.spice]\ntmax_fraction = 1\n",
     r"scene s.toml [methods.spice] tmax_fraction (.tran TMAX as a fraction of the switching period) must be in "
     r"[1e-06, 1); got 1"),
    (BUCK + "[methods.spice]\nmethod = \"euler\"\n",
     r"scene s.toml [methods.spice] method must be 'trap' or 'gear'; got 'euler'"),
    (BUCK + "[methods.spice]\nswitch_ron = 10\nswitch_roff = 5\n",
     r"scene s.toml [methods.spice] switch_roff must be above switch_ron = 10; got 5"),
    (BUCK + "[methods.spice]\ndiode_is = \"abc\"\n", r"scene s.toml [methods.spice] diode_is must be a number"),
    (BUCK + "[checks]\nmode_agreement = 2\n",
     r"scene s.toml [checks] mode_agreement must be in (0, 1] (a fraction); got 2"),
    (BUCK + "[checks]\nvout_mean_rel = true\n", r"scene s.toml [checks] vout_mean_rel must be a number; got True"),
    (BUCK + "[checks]\nlambda_settle = 1e-6\n",
     r"scene s.toml [checks] lambda_settle does not apply to this scene (buck, pwm); valid keys: vout_mean_rel"),
    ('converter = "prc"\n[methods.lcp]\nrtol = 1e-6\n',
     r"scene s.toml [methods.lcp] rtol gives the periodic steady state: it needs [run] start = 'steady'; got start = "
     r"'rest' (the model's default)"),
    (FAST + "[methods.lcp]\ntheta = 0.5\n",
     r"scene s.toml [methods.lcp] theta does not apply to a control scene (smc-implicit); valid keys: h"),
    (FAST + "[methods.spice]\nreltol = 1e-4\n",
     r"scene s.toml [methods.spice]: an smc-implicit scene runs no ngspice; remove [methods.spice]"),
    (FAST.replace("t_end = 0.002", "t_end = 100"), r"scene s.toml [run] t_end must be in (0, 10] s; got 100"),
    (FAST.replace("t_end = 0.002", "periods = 3"),
     r"scene s.toml [run] periods does not apply to a control scene (smc, smc-implicit); valid keys: t_end"),
    (BUCK + "[methods]\nlcp = 5\n", r"scene s.toml [methods.lcp] must be a table; got int 5"),
    # --- circuit scenes (a netlist's compare) ----------------------------------------------------------------
    ('circuit = "/etc/passwd.cir"\n', r"scene s.toml: circuit must be a relative path to a .cir file without '..'"),
    ('circuit = "../x.cir"\n', r"scene s.toml: circuit must be a relative path to a .cir file without '..'"),
    ('circuit = "sepic.toml"\n', r"scene s.toml: circuit must be a relative path to a .cir file without '..'"),
    ('circuit = "nowhere.cir"\n', r"scene s.toml: circuit 'nowhere.cir' is neither beside the scene"),
    ('circuit = 5\n', r"scene s.toml: circuit must be a string; got 5"),
    ('circuit = "sepic.cir"\nconverter = "buck"\n', r"scene s.toml: a circuit scene takes neither converter nor "
                                                      r"control; valid keys: name, circuit,"),
    ('circuit = "sepic.cir"\n[params]\nDx = 0.5\n', r"unknown key 'Dx' in scene s.toml [params]; valid keys: "),
    ('circuit = "sepic.cir"\n[params]\nD = 2\n', r"scene s.toml [params]: "),   # the compile refuses PW < 0
    ('circuit = "sepic.cir"\n[run]\nt_end = 1\n', r"unknown key 't_end' in scene s.toml [run]; valid keys: start, "
                                                     r"periods, window"),
    ('circuit = "sepic.cir"\n[run]\nperiods = 5\n', r"scene s.toml [run] window must be in [1, periods = 5]; got 10"),
    ('circuit = "sepic.cir"\n[methods.lcp]\nh = 1\n', r"scene s.toml [methods.lcp] h must be a positive number "
                                                         r"below the circuit's period"),
    ('circuit = "sepic.cir"\n[methods.lcp]\ntheta = 1\n', r"unknown key 'theta' in scene s.toml [methods.lcp]; "
                                                             r"valid keys: h"),
    ('circuit = "sepic.cir"\n[checks]\nvout_mean_rel = 1e-3\n', r"unknown key 'vout_mean_rel' in scene s.toml "
                                                                   r"[checks]; valid keys: mean_rel, ripple_rel"),
    ('circuit = "sepic.cir"\n[checks]\nmode_agreement = 2\n',
     r"scene s.toml [checks] mode_agreement must be in (0, 1] (a fraction); got 2"),
]


@pytest.mark.parametrize("body, message", BAD, ids=[m[:60] for _, m in BAD])
def test_a_bad_scene_is_refused_at_load_naming_the_file_the_key_and_the_value(body, message, tmp_path):
    with pytest.raises(ParameterError) as caught:
        load_scene(_scene(tmp_path, body))
    text = str(caught.value)
    assert "\n" not in text and text.startswith(message), text


def test_a_scene_file_that_is_not_utf8_toml_or_too_large_is_refused(tmp_path):
    (tmp_path / "bin.toml").write_bytes(b'converter = "\xff"\n')
    with pytest.raises(ParameterError, match=r"^scene bin.toml: not a readable TOML file \("):
        load_scene(tmp_path / "bin.toml")
    (tmp_path / "big.toml").write_text(BUCK + "#" * (1 << 20))
    with pytest.raises(ParameterError, match=r"^scene big.toml: a scene file must be at most 1048576 bytes; got "):
        load_scene(tmp_path / "big.toml")


def test_every_scene_of_the_project_passes_the_strict_checks():
    assert len(load_scenes(sorted(SCENE_DIR.glob("*.toml")))) == len(list(SCENE_DIR.glob("*.toml"))) == 19
    assert {s.name for s in scenes_of("default")} >= {"buck-dcm", "prc", "boost-smc-implicit", "netlist-sepic",
                                                      "netlist-voltage-loop-buck"}


def test_a_circuit_scene_names_a_netlist_beside_it_or_a_shipped_one(tmp_path):
    """circuit = "FILE.cir": the scene's own directory first (a user's circuit), then netlists/circuits; its
    [params] are the file's names; the thresholds those of a netlist's compare."""
    from validation.defaults import THRESHOLDS
    shipped = load_scene(_scene(tmp_path, 'circuit = "sepic.cir"\n[params]\nD = 0.3\n[checks]\nmean_rel = 2e-3\n'))
    assert shipped.control == "circuit" and Path(shipped.circuit).parent.name == "circuits"
    assert shipped.checks == {**THRESHOLDS["circuit"], "mean_rel": 2e-3} and shipped.params == {"D": 0.3}
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "sepic.cir").write_text((Path(shipped.circuit)).read_text().replace("D=0.4", "D=0.35"))
    own = load_scene(_scene(tmp_path, 'circuit = "mine/sepic.cir"\n', "own.toml"))
    assert Path(own.circuit) == tmp_path / "mine" / "sepic.cir" and own.converter == "sepic.cir"


@pytest.mark.spice
def test_a_circuit_scene_runs_the_netlists_compare(tmp_path, ngspice):
    """The scene's result is compare_circuit's: its checks and metrics; a threshold the scene tightens below what
    is measured fails it (the scene's [checks] reach the comparison)."""
    from validation.suite import _run_scene
    passed = _run_scene(load_scene(_scene(tmp_path, 'circuit = "sepic.cir"\n', "a.toml")))
    # (the SEPIC does not settle from rest within 600 periods: ngspice's own run is checked to approach its run from
    # the orbit, the comparison's spice_own_start)
    assert passed.ok and [c[0] for c in passed.checks] == ["mean_rel", "ripple_rel", "mode_agreement",
                                                           "spice_own_start"]
    assert passed.metrics["v(out)_mean_rel_error"] < 1e-3 and "scenes/a/overlay.png" in passed.files
    tight = _run_scene(load_scene(_scene(tmp_path, 'circuit = "sepic.cir"\n[checks]\nmean_rel = 1e-9\n', "b.toml")))
    assert not tight.ok and tight.reason == "failed checks: mean_rel"


def test_a_bad_scene_file_fails_the_report_command_before_anything_runs(tmp_path, monkeypatch, capsys):
    from validation import suite

    def ran(*args, **kwargs):
        raise AssertionError("the suite ran")
    monkeypatch.setattr(suite, "run_suite", ran)
    scenes = tmp_path / "scenes"
    scenes.mkdir()
    _scene(scenes, FAST, "good.toml")
    _scene(scenes, BUCK + "[methods.lcp]\ntheta = 2\n", "bad.toml")
    monkeypatch.chdir(tmp_path)
    before = tree(tmp_path)
    code, out, err = cli(capsys, "report", "scenes")
    assert code == 2 and out == ""
    assert one_line(err) == "scene bad.toml [methods.lcp] theta must be in [0.5, 1]; got 2"
    assert tree(tmp_path) == before                                    # no reports/ directory either
    code, _, err = cli(capsys, "report", "nosuch")
    assert code == 2 and one_line(err).startswith("TARGET must be a suite (") and err.endswith("; got 'nosuch'\n")
    (tmp_path / "empty").mkdir()
    code, _, err = cli(capsys, "report", "empty")
    assert code == 2 and one_line(err) == "scene directory 'empty' holds no *.toml scene file"


# --- E and B: a user's scenes run, every string escaped ------------------------------------------------------------

#: Tags and attributes the report writes; anything else in the page came from data.
TAGS = {"html", "head", "meta", "title", "style", "body", "h1", "h2", "h3", "p", "table", "tr", "th", "td", "a",
        "section", "div", "small", "code", "img", "details", "summary", "b", "i"}
ATTRIBUTES = {"charset", "class", "id", "href", "src", "alt"}


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.text = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, attrs))

    handle_startendtag = handle_starttag

    def handle_data(self, data):
        self.text.append(data)


def _check_page(index: Path, must_show: list[str]) -> None:
    raw = index.read_text()
    page = _Page()
    page.feed(raw)
    for tag, attrs in page.tags:
        assert tag in TAGS, tag
        for name, value in attrs:
            assert name in ATTRIBUTES, (tag, name, value)
            if name in ("href", "src") and not value.startswith("#"):
                assert ":" not in value and not value.startswith("/") and ".." not in value.split("/"), value
                assert (index.parent / value).resolve().is_relative_to(index.parent.resolve()), value
                assert (index.parent / value).is_file(), value
    text = "".join(page.text)
    for shown in must_show:
        assert shown in text                                # shown as text, unescaped by the parser
    for tag in re.findall(r"<\s*([a-zA-Z][a-zA-Z0-9]*)", raw):
        assert tag.lower() in TAGS, tag          # no tag from data (<script>, <img onerror>)


def test_a_users_scene_file_and_directory_run_and_every_string_is_escaped(tmp_path, monkeypatch, capsys):
    work = tmp_path / "work"
    (work / "mine").mkdir(parents=True)
    nasty_file = "x'\"<b>&.toml"
    _scene(work / "mine", f'name = "fast-1"\ndescription = {json.dumps(NASTY)}\nsuites = ["a.b", "c-d"]\n' + FAST,
           nasty_file)
    _scene(work / "mine", f'name = "fast-2"\ndescription = {json.dumps(NASTY)}\n' + FAST, "two.toml")
    monkeypatch.chdir(work)
    outside = tree(tmp_path)
    # The default --out reports/STEM needs a safe STEM: this one is not, so it is refused before the run...
    code, out, err = cli(capsys, "report", f"mine/../mine/{nasty_file}", "--workers", "1")
    assert code == 2 and one_line(err).startswith("the default --out reports/STEM (give --out): STEM of ")
    assert tree(tmp_path) == outside
    # ...and with --out the file runs (its checks may fail on 2 ms: exit 1; the page is what counts here).
    code, out, err = cli(capsys, "report", f"mine/../mine/{nasty_file}", "--out", "single", "--workers", "1")
    assert code in (0, 1), err
    index = work / "single" / "index.html"
    _check_page(index, [NASTY, nasty_file, f"mine/../mine/{nasty_file}"])
    assert sorted(p.relative_to(work / "single").as_posix() for p in (work / "single").rglob("*")) == [
        ".pcsuite-report.json", "index.html", "metrics.json", "scenes", "scenes.csv", "scenes/fast-1",
        "scenes/fast-1/lcp.parquet", "scenes/fast-1/scope.html", "scenes/fast-1/waveforms.png", "summary.csv"]
    assert json.loads((work / "single" / "metrics.json").read_text())["suite"] == f"mine/../mine/{nasty_file}"
    # A directory: every *.toml in it, default --out reports/DIRNAME.
    code, out, err = cli(capsys, "report", "mine", "--workers", "1")
    assert code in (0, 1), err
    index = work / "reports" / "mine" / "index.html"
    assert out.startswith(f"wrote reports{os.sep}mine{os.sep}index.html")
    _check_page(index, [NASTY])
    assert sorted(p.name for p in (index.parent / "scenes").iterdir()) == ["fast-1", "fast-2"]
    after = tree(tmp_path)
    new = sorted(set(after) - set(outside))
    assert all(p.startswith(("work/single", "work/reports")) for p in new), new   # nothing outside --out
    assert all(after[p] == outside[p] for p in outside)


def test_scene_section_escapes_even_a_scene_built_in_code(tmp_path):
    """Defence in depth: a Scene that skipped load_scene still cannot inject markup, and its unsafe name cannot
    become a file name (the report refuses the section's files)."""
    from validation.report import write_report
    from validation.suite import SceneResult, scene_section
    scene = Scene(name="x' onerror='alert(1)", converter="buck<b>", description=NASTY, params={"L": NASTY},
                  path=f"/tmp/{NASTY}.toml")
    result = SceneResult(scene, ok=False, reason=NASTY, checks=[("check<i>", 1.0, 2.0, True)],
                         metrics={NASTY: NASTY}, notes=[NASTY], files={"scenes/x' onerror='alert(1)/overlay.png": b"png"})
    section = scene_section(result)
    assert "onerror='alert(1)" not in section.html and "<script>" not in section.html
    assert "src='scenes/x%27%20onerror%3D%27alert%281%29/overlay.png'" in section.html
    with pytest.raises(ParameterError, match=r"file \"scenes/x' onerror='alert\(1\)/overlay.png\"|the part must be"):
        write_report([section], tmp_path / "r", "t")
    section.files = {}
    index = write_report([section], tmp_path / "r", NASTY, options={"x": NASTY})
    page = _Page()
    page.feed(index.read_text())
    assert all(name in ATTRIBUTES for _, attrs in page.tags for name, _ in attrs)
    assert all(tag in TAGS for tag, _ in page.tags)

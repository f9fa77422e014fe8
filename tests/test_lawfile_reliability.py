"""Law files are code (issue 47, items 9-14): the help and the docs say so; whatever a file
does while it loads (an exception, any ``sys.exit``) is one line naming it, exit status 2;
taken names, improper or non-scalar priors, priors without an inverse CDF, overlong names
and labels the figures cannot draw are refused on load, before any work; user text is
escaped in the Markdown outputs as in the HTML; and the first order refuses a force that
is NaN on the amplitudes it integrates, as the backbone does.

Every refusal here happens on load: no test fits anything.
"""

from __future__ import annotations

import dataclasses
import math
import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

from beadrod.inference.model.likelihood import scene_quantities
from beadrod.models import registry
from beadrod.models.lawfile import NAME_MAX, LawFileError, load_law_file
from beadrod.models.scene import builtin_scene
from beadrod.workflows import lawfiles
from beadrod.workflows.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENE = scene_quantities(builtin_scene("paper"))
HERTZ = "jnp.where(t, 4/3 * young/(2*(1-poisson**2)) * jnp.sqrt(radius) * d**1.5, 0.0)"

LAW = """
import jax.numpy as jnp
import numpyro.distributions as dist
{top}
NAME = {name}
PRIORS = {priors}
{extra}
def force(delta, *, young, poisson, radius):
    t = delta > 0
    d = jnp.where(t, delta, 1.0)
    {pre}
    return {body}
"""


def _law_file(tmp_path: Path, *, name: str = "'lf_ok'", top: str = "", extra: str = "",
              priors: str = '{"young": dist.Uniform(150e9, 250e9)}', pre: str = "",
              body: str = HERTZ, file: str = "law.py") -> Path:
    f = tmp_path / file
    f.write_text(textwrap.dedent(LAW).format(top=top, name=name, priors=priors, extra=extra,
                                             pre=pre, body=body))
    return f


@pytest.fixture(autouse=True)
def _registry_as_it_was():
    """A law file loaded through the command line stays registered in the process: take
    each test's laws out again, so names do not leak from one test into the next."""
    before = set(registry.law_names())
    yield
    for name in set(registry.law_names()) - before:
        registry.unregister(name)


def _refused(capsys, argv: list[str], path: Path, *words: str) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("beadrod: warning: ")]
    assert len(lines) == 1 and lines[0].startswith("beadrod: error: law file "), err
    assert str(path) in err and "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    return err


# ------------------------------------------------------------------- 9: a law file is code
@pytest.mark.parametrize("command", ["laws", "shift", "fit", "compare", "rungs"])
def test_law_file_help_says_it_is_code(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "A law file is Python code" in text and "source you trust" in text


def test_adding_a_law_doc_says_a_law_file_is_code():
    text = " ".join((ROOT / "docs" / "adding-a-law.md").read_text().split())
    assert "A law file is code." in text and "only from a source you trust" in text


# ------------------------------------------------------------ 10: exceptions and exits
@pytest.mark.parametrize("top,said", [
    ("import sys\nsys.exit(0)", "called sys.exit(0) on import"),
    ("raise SystemExit(3)", "called sys.exit(3) on import"),
    ("raise SystemExit('bye')", "called sys.exit('bye') on import"),
    ("raise RuntimeError('boom')", "raised RuntimeError on import: boom"),
])
def test_an_exit_or_exception_on_import_is_one_line(tmp_path, capsys, top, said):
    f = _law_file(tmp_path, top=top)
    _refused(capsys, ["laws", "--law-file", str(f)], f, said)


def test_fit_with_an_exiting_law_file_exits_2_not_0(tmp_path, capsys):
    # was: exit status 0, having done nothing
    f = _law_file(tmp_path, top="import sys\nsys.exit(0)")
    _refused(capsys, ["fit", "--law", "lf_ok", "--law-file", str(f), "--out",
                      str(tmp_path / "out"), "--quiet"], f, "sys.exit(0)")


def test_an_exit_inside_force_while_checking_is_one_line(tmp_path, capsys):
    f = _law_file(tmp_path, top="import sys", pre="sys.exit(4)")
    _refused(capsys, ["laws", "--law-file", str(f)], f, "force called sys.exit(4)")


def test_an_interrupt_while_loading_is_still_an_interrupt(tmp_path, capsys):
    f = _law_file(tmp_path, top="raise KeyboardInterrupt")
    with pytest.raises(KeyboardInterrupt):
        load_law_file(f, SCENE)
    assert main(["laws", "--law-file", str(f)]) == 130
    assert "interrupted" in capsys.readouterr().err


# ------------------------------------------------------------------- 11: taken names
@pytest.mark.parametrize("name,owner", [
    ("'baseline'", "the law-free baseline"),
    ("'hertz'", "the law 'hertz' (built-in)"),
    ("'HERTZ'", "the law 'hertz' (built-in)"),   # one file name on a case-blind disk
])
def test_a_taken_name_is_refused_in_one_line(tmp_path, capsys, name, owner):
    f = _law_file(tmp_path, name=name)
    _refused(capsys, ["laws", "--law-file", str(f)], f, "is taken by " + owner,
             "choose another NAME")


def test_reserved_names_come_from_the_registry(tmp_path):
    """Every registered law's name is taken, not a list: a law registered at run time
    (here a renamed Hertz) takes its name too, and frees it when it goes."""
    extra = registry.register(dataclasses.replace(registry.get_law("hertz"), name="lf_new",
                                                  source="a test"))
    f = _law_file(tmp_path, name="'lf_new'")
    with pytest.raises(LawFileError, match=r"taken by the law 'lf_new' \(a test\)"):
        lawfiles.load([str(f)])
    registry.unregister(extra.name)
    assert lawfiles.load([str(f)]) == ["lf_new"]


def test_two_files_with_one_name_the_second_is_refused(tmp_path, capsys):
    a = _law_file(tmp_path, name="'lf_twice'", file="a.py")
    b = _law_file(tmp_path, name="'lf_twice'", file="b.py")
    err = _refused(capsys, ["laws", "--law-file", str(a), "--law-file", str(b)], b,
                   "is taken by the law 'lf_twice'")
    assert str(a) in err
    # the same file twice is one law
    assert main(["laws", "--json", "--law-file", str(a), "--law-file", str(a)]) == 0


# --------------------------------------------------------- 12: the contract, on load
@pytest.mark.parametrize("priors,said", [
    ('{"young": dist.ImproperUniform(dist.constraints.positive, (), ())}',
     "(ImproperUniform) has no inverse CDF"),
    ('{"young": dist.VonMises(2e11, 1.0)}', "(VonMises) has no inverse CDF"),
    ('{"young": dist.Uniform(jnp.array([150e9, 160e9]), 250e9)}', "batch shape (2,)"),
    ('{"young": dist.MultivariateNormal(jnp.full(2, 2e11), jnp.eye(2))}',
     "event shape (2,)"),
])
def test_priors_without_a_scalar_inverse_cdf_are_refused(tmp_path, capsys, priors, said):
    f = _law_file(tmp_path, priors=priors)
    _refused(capsys, ["laws", "--law-file", str(f)], f, "PRIORS['young']", said)


def test_a_law_prior_object_must_be_proper(tmp_path):
    f = _law_file(tmp_path, top="from beadrod.models.law import Prior",
                  priors='{"young": Prior("uniform", 250e9, 150e9)}')
    with pytest.raises(LawFileError, match=r"PRIORS\['young'\] = .* is not a proper prior"):
        load_law_file(f, SCENE)
    f = _law_file(tmp_path, top="from beadrod.models.law import Prior",
                  priors='{"young": Prior("cauchy", 2e11, 1e10)}')
    with pytest.raises(LawFileError, match="kind must be one of"):
        load_law_file(f, SCENE)


@pytest.mark.parametrize("name", [repr("a" * 300), repr("a" * (NAME_MAX + 1)),
                                  repr("lf_nl\n"), repr("lf-dash"), repr("lf.dot"),
                                  repr("élan"), "None", "42"])
def test_a_name_that_cannot_be_a_file_name_is_refused_on_load(tmp_path, name):
    f = _law_file(tmp_path, name=name)
    with pytest.raises(LawFileError, match="NAME is missing or not a name") as err:
        load_law_file(f, SCENE)
    assert len(str(err.value)) < 400   # the name is cut short in the message


def test_the_longest_name_loads(tmp_path):
    f = _law_file(tmp_path, name=repr("a" * NAME_MAX))
    assert load_law_file(f, SCENE).name == "a" * NAME_MAX


def test_an_overlong_name_is_refused_before_fitting(tmp_path, capsys):
    # was: "file name too long" after 116 s of fitting
    f = _law_file(tmp_path, name=repr("a" * 300))
    _refused(capsys, ["fit", "--law", "a" * 300, "--law-file", str(f), "--out",
                      str(tmp_path / "out"), "--quiet"], f, "at most 64 characters")


@pytest.mark.parametrize("extra,said", [
    ("LABEL = None", "LABEL must be a str"),
    ("LABEL = 'two\\nlines'", "LABEL must be one line"),
    ("REFERENCE = 3", "REFERENCE must be a str"),
    ("ADHESIVE = 'False'", "ADHESIVE must be a bool"),
])
def test_optional_entries_have_their_types(tmp_path, extra, said):
    f = _law_file(tmp_path, extra=extra)
    with pytest.raises(LawFileError, match=said):
        load_law_file(f, SCENE)


# ------------------------------------------------------- 13: labels and the Markdown
@pytest.mark.parametrize("label,said", [
    (r"$\undefinedmacro{x}$", r"Unknown symbol: \undefinedmacro"),
    (r"Hertz $x^$", "is not math text the figures can draw"),
    ("cost $5", "unmatched $"),
])
def test_a_label_the_figures_cannot_draw_is_refused_on_load(tmp_path, capsys, label, said):
    f = _law_file(tmp_path, extra=f"LABEL = {label!r}")
    _refused(capsys, ["laws", "--law-file", str(f)], f, "LABEL", said)


def test_a_label_with_math_loads(tmp_path):
    f = _law_file(tmp_path, extra=r"LABEL = r'Hertz, $E^*\sqrt{R}\,\delta^{3/2}$ (\$0)'")
    assert lawfiles.load([str(f)]) == ["lf_ok"]
    assert lawfiles.label_problem("plain <b>text</b>") is None


SCRIPT = "<script>alert(1)</script>"
EVIL = f"{SCRIPT} ![x](http://tracker/x.png) [y](javascript:alert(2)) &lt;b&gt; $\\eta$"


def test_markdown_escape_keeps_the_projects_markup():
    from beadrod.workflows.report.markdown import code_fence, md_escape

    out = md_escape(f"**{EVIL}** `a <b> c` k < 0.7, R&D")
    assert "<script" not in out and "&lt;script>" in out
    assert not re.search(r"(?<!\\)\]\(", out)         # no link, no image
    assert "&amp;lt;b&amp;gt;" in out                  # an entity stays its characters
    assert out.startswith("**") and "$\\eta$" in out     # bold and math kept
    assert "`a <b> c`" in out and "k < 0.7, R&D" in out  # code span verbatim, lone < and &
    assert code_fence('{"label": "```"}').startswith("````\n")


def test_user_text_is_escaped_in_report_md_and_comparison_md(tmp_path):
    from beadrod.workflows.report.document import comparison_table, render_report

    res = {"laws": [{"name": "lf_evil", "label": EVIL, "status": "ok", "log_z": -3.0,
                     "log_z_err": 0.1, "rung": "backbone",
                     "params": [{"name": "young", "mean": 2e11, "sd": 1e9, "q05": 1.9e11,
                                 "q95": 2.1e11, "unit": "Pa"}]},
                    {"name": "hertz", "label": "Hertz", "status": "failed",
                     "failures": [SCRIPT]}],
            "preferred": "lf_evil", "figures": []}
    md_path, html_path = render_report(res, tmp_path)
    comparison_md, _ = comparison_table(res)
    for md in (md_path.read_text(), comparison_md):
        assert "&lt;script>" in md and "$\\eta$" in md
        assert "<script" not in md and "<b>" not in md
        assert not re.search(r"(?<!\\)\]\(", md)     # no link, no image
    assert "<script" not in html_path.read_text()


# -------------------------------------------------- 14: first order checks the force
NAN_PAST = f"jnp.where(delta > 1.2e-7, jnp.nan, {HERTZ})"   # delta0 = 5.3e-8 m


def test_first_order_refuses_a_force_that_is_nan_on_its_arc(tmp_path, capsys):
    """The force is NaN past 2.25 delta0 while its tangent there is 0 (jnp.where): the
    averaged stiffness alone was finite (-0.2955 at x = 1.9), the backbone NaN."""
    f = _law_file(tmp_path, name="'lf_nan'", body=NAN_PAST)
    law = load_law_file(f, SCENE)
    kw = law.resolve(SCENE, {"young": 2e11})
    shift = np.asarray(law.shift(np.array([0.5, 1.9]), rung="first_order", **kw))
    assert math.isfinite(shift[0]) and math.isnan(shift[1])
    assert main(["shift", "--law", "lf_nan", "--law-file", str(f), "--method",
                 "first_order", "--x", "0.5", "1.9"]) == 2
    assert "gives no finite shift at x = 1.9" in capsys.readouterr().err

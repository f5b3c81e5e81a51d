"""The table of extreme cases and bad input (``docs/stability.md``), written from what the tests
observed, never by hand.

A test asks for the ``stability_case`` fixture and describes each case it checks, then records
what it saw::

    def test_all_zero(stability_case):
        case = stability_case("all-zero errors", area="error model", given="ε = 0 at Δn = 2..50")
        fit = fit_error(PERIODS, zeros)
        case.observe(alpha=fit.alpha, lam=fit.lam, quality=fit.quality)
        assert fit.quality == "zero"

``pytest --stability-table docs/stability.md`` then writes one Markdown row per case: its area,
name, input, the observed values (floats to 4 significant digits, messages verbatim) and whether
the test that observed it passed. Hypothesis tests get a row each without asking, in the area
"fuzzing", with the number of examples hypothesis reports having run (its statistics).

Imported by ``tests/conftest.py`` (the hooks and the fixture must live in a conftest namespace).
"""
from __future__ import annotations

import datetime
import re
from pathlib import Path

import pytest

_CASES = pytest.StashKey[list]()
_OUTCOMES = pytest.StashKey[dict]()
_FUZZ = pytest.StashKey[dict]()


def pytest_addoption(parser):
    parser.addoption("--stability-table", metavar="PATH", default=None,
                     help="write the Markdown table of the extreme and bad-input cases this run observed "
                          "(the stability_case fixture) to PATH")


def pytest_configure(config):
    config.stash[_CASES] = []
    config.stash[_OUTCOMES] = {}
    config.stash[_FUZZ] = {}


def _format(value) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    return str(value)


class StabilityCase:
    """One row of the table: ``name``, ``area``, ``given`` (the input) and what was observed."""

    def __init__(self, nodeid: str, name: str, area: str, given: str):
        self.nodeid = nodeid
        self.name = name
        self.area = area
        self.given = given
        self.observed: dict[str, object] = {}

    def observe(self, **values) -> "StabilityCase":
        """Record observed values (in call order; a key given again replaces its value)."""
        self.observed.update(values)
        return self

    def observed_text(self) -> str:
        if not self.observed:
            return "(nothing observed: the test stopped before)"
        return "; ".join(f"{k}={_format(v)}" for k, v in self.observed.items())


@pytest.fixture
def stability_case(request):
    """``stability_case(name, area=..., given=...)`` → a :class:`StabilityCase` to ``observe()``."""
    def make(name: str, area: str, given: str) -> StabilityCase:
        case = StabilityCase(request.node.nodeid, name, area, given)
        request.config.stash[_CASES].append(case)
        return case
    return make


_PASSING = re.compile(r"(\d+) passing")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    outcomes = item.config.stash[_OUTCOMES]
    if report.failed:
        outcomes[item.nodeid] = "FAILED"
    elif report.skipped:
        outcomes.setdefault(item.nodeid, "skipped")
    elif report.when == "call":
        outcomes.setdefault(item.nodeid, "passed")
    stats = getattr(item, "hypothesis_statistics", None)
    if report.when == "call" and stats is not None:
        settings = getattr(item.obj, "_hypothesis_internal_use_settings", None)
        item.config.stash[_FUZZ][item.nodeid] = (
            getattr(settings, "max_examples", None), sum(int(n) for n in _PASSING.findall(stats)),
            _what(item))


def _what(item) -> str:
    """What a fuzz test feeds: its docstring's first line, else its module's first sentence."""
    doc = (item.obj.__doc__ or "").strip().split("\n")[0]
    if not doc:
        module_doc = " ".join((getattr(item.module, "__doc__", None) or "").split())
        doc = re.split(r"(?<=[.:])\s", module_doc, maxsplit=1)[0].rstrip(".:")
    return doc


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ").strip()


def _renderer() -> str:
    try:
        from rrcache.gl import context
        ctx = context._ctx
        return ctx.info["GL_RENDERER"] if ctx is not None else "no GL context was made"
    except Exception as err:  # the table is still written without the renderer's name
        return f"unknown ({type(err).__name__})"


def pytest_sessionfinish(session, exitstatus):
    path = session.config.getoption("--stability-table")
    if not path:
        return
    config = session.config
    outcomes = config.stash[_OUTCOMES]
    cases = list(config.stash[_CASES])
    for nodeid, (max_examples, passing, doc) in config.stash[_FUZZ].items():
        name = nodeid.split("::")[-1].removeprefix("test_").replace("_", " ")
        case = StabilityCase(nodeid, name, "fuzzing (hypothesis)",
                             f"max_examples={max_examples}" + (f": {doc}" if doc else ""))
        case.observe(examples_run=passing)
        cases.append(case)
    areas: list[str] = []
    for case in cases:
        if case.area not in areas:
            areas.append(case.area)
    failed = sum(1 for c in cases if outcomes.get(c.nodeid) == "FAILED")
    lines = [
        "# Extreme cases and bad input: observed behaviour",
        "",
        "Generated by the test run, not written by hand: every row is a case a test checked and what it",
        "observed (`tests/stability_table.py`). Regenerate with",
        "",
        "```sh",
        "python -m pytest -q tests/test_stability_models.py tests/test_stability_render.py \\",
        "    tests/test_stability_cli.py tests/test_profile_store.py \\",
        "    tests/test_cli_profile.py::test_resume_after_sigkill \\",
        "    tests/test_cli_profile.py::test_sigint_exits_130_and_keeps_the_store \\",
        "    tests/test_model_fuzz.py tests/test_frontend_fuzz.py tests/test_session_fuzz.py \\",
        "    tests/test_safety_includes.py tests/test_safety_cli.py tests/test_safety_store.py \\",
        "    tests/test_safety_budgets.py tests/test_safety_profile_doc.py tests/test_safety_fuzz.py \\",
        "    tests/test_safety_reads.py tests/test_safety_writes.py tests/test_safety_exits.py \\",
        "    tests/test_inline_shaders.py --stability-table docs/stability.md",
        "```",
        "",
        f"Run {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; GL renderer: {_renderer()}; "
        f"{len(cases)} cases, {failed} failed.",
        "",
    ]
    for area in areas:
        lines += [f"## {area}", "", "| case | input | observed | result | test |", "|---|---|---|---|---|"]
        for case in (c for c in cases if c.area == area):
            result = outcomes.get(case.nodeid, "not run")
            test = case.nodeid
            lines.append(f"| {_cell(case.name)} | {_cell(case.given)} | {_cell(case.observed_text())} | "
                         f"{result} | `{_cell(test)}` |")
        lines.append("")
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines), encoding="utf-8")

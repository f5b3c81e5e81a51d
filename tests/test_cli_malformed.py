"""Every malformed shader in the test corpora through ``rrcache nodes``: exit code 2, exactly one
``file:line:col: message`` line on stderr, no Python traceback (``--debug`` shows it).

The corpora: syntax errors (tests/glsl/malformed, header ``// expect: L:C message``), semantic
errors (tests/glsl/semantic_errors, same header) and preprocessor errors (tests/glsl/pp/bad,
header ``// ERROR [file:]L:C message``).
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from rrcache.cli import main

HERE = Path(__file__).parent / "glsl"
CASES = sorted(
    list((HERE / "malformed").glob("*.frag")) + list((HERE / "semantic_errors").glob("*.frag"))
    + list((HERE / "pp" / "bad").glob("*.frag")),
    key=str,
)
_EXPECT = re.compile(r"//\s*(?:expect:|ERROR)\s+(?:(\S+?):)?(\d+):(\d+)\s+(.*)")


def _expectation(path: Path):
    match = _EXPECT.search(path.read_text(encoding="utf-8", errors="replace").splitlines()[0])
    assert match, f"{path} lacks an expectation header"
    file, line, col, message = match.groups()
    return (file or path.name), int(line), int(col), message.strip()


def test_there_are_at_least_forty_malformed_inputs():
    assert len(CASES) >= 40


@pytest.mark.parametrize("path", CASES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_cli_reports_one_located_error_without_traceback(path, capsys):
    file, line, col, message = _expectation(path)
    with pytest.raises(SystemExit) as exit_info:
        main(["nodes", str(path)])
    assert exit_info.value.code == 2
    captured = capsys.readouterr()
    err_lines = [l for l in captured.err.splitlines() if l.strip()]
    assert len(err_lines) == 1, captured.err
    assert "Traceback" not in captured.err
    expected_file = (path.parent / file).resolve() if "/" in file else Path(file)
    assert f"{expected_file}:{line}:{col}:" in err_lines[0] or f"{file}:{line}:{col}:" in err_lines[0]
    # the expectation's message fragment (minus quoting differences) appears in the message
    assert message.split("'")[0].strip().lower()[:20] in err_lines[0].lower()


def test_debug_flag_shows_the_traceback(capsys):
    """--debug adds the traceback and keeps the error's exit code (2, not the interpreter's 1)."""
    path = HERE / "malformed" / "01_missing_semicolon.frag"
    with pytest.raises(SystemExit) as done:
        main(["--debug", "nodes", str(path)])
    err = capsys.readouterr().err
    assert done.value.code == 2
    assert "Traceback (most recent call last)" in err and "ParseError" in err
    assert err.strip().splitlines()[-1].startswith("rrcache: error: ") and "01_missing_semicolon.frag:4:5" in err

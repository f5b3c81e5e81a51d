"""Every warning of a profile, in words: one list for the command's summary and the report.

The run's own warnings (kept in ``profile.json``'s ``warnings``: a session shorter than the
largest period, a texture that could not be read as asked ...) come first, then what its
measurements imply: the original's times too noisy to rely on (while the ceiling was measured,
between timing runs, while a level was validated), the budget stopping the training, a level
that fell back from the models' choice, a level below 30 dB.

>>> from types import SimpleNamespace as N
>>> prof = N(warnings=["40 training frames do not reach the steady state of period 50"], measured_ceiling=None,
...          timing_noise=0.23, timing_reliable=False, budget_stopped=False, nodes=[], selections=[])
>>> for line in run_warnings(prof): print(line)
40 training frames do not reach the steady state of period 50
the original's times varied by ±23% between timing runs of the same frame: other work on the machine made the timings unreliable; profile again on a quieter machine
"""
from __future__ import annotations

from rrcache.harness.timing import UNRELIABLE_NOISE
from rrcache.model.psnr import VISIBLE_DB


def ceiling_noise(ceiling) -> list[str]:
    """The warning of a ceiling measured while the machine was busy (none when it was quiet)."""
    if ceiling is None or not ceiling.noise > UNRELIABLE_NOISE:
        return []
    return [f"the original's repeated frames varied by ±{ceiling.noise:.0%} while the ceiling was measured: other "
            "work on the machine made it unreliable; profile again on a quieter machine (the profile folder keeps "
            "it: use --fresh)"]


def run_warnings(prof, stored: bool = True) -> list[str]:
    """Every warning of ``prof`` (see the module docstring), one sentence each; ``stored=False``
    leaves out the run's own (a command that printed them as they came)."""
    out = list(getattr(prof, "warnings", None) or []) if stored else []
    out += ceiling_noise(prof.measured_ceiling)
    noise = prof.timing_noise
    if noise is not None and not prof.timing_reliable:
        out.append(f"the original's times varied by ±{noise:.0%} between timing runs of the same frame: other work "
                   "on the machine made the timings unreliable; profile again on a quieter machine")
    if prof.budget_stopped:
        late = sum(1 for n in prof.nodes if not n.trained and n.note and "budget" in n.note)
        out.append(f"the training budget ran out: {late} nodes were not trained (--budget SECONDS trains more)")
    noisy = [s.label for s in prof.selections
             if s.measured_noise is not None and s.measured_noise > UNRELIABLE_NOISE]
    if noisy:
        out.append(f"{', '.join(noisy)} measured while the original's frame times varied by more than "
                   f"{UNRELIABLE_NOISE:.0%}: the machine's load made those speed-ups unreliable")
    for s in prof.selections:
        if s.fallback:
            out.append(f"{s.label}: {s.fallback}")
        if getattr(s, "level_met", None) is False:
            out.append(f"{s.label}: MISSED its level: {s.level_note}")
    marked = [s.label for s in prof.selections if s.visible_artifacts]
    if marked:
        out.append(f"{', '.join(marked)}: {visible_words(prof)}: visible artifacts (a choice, not a default)")
    return out


def visible_words(prof) -> str:
    """How the profile judged visible artifacts: measured FLIP where validation measured it, else
    the predicted PSNR."""
    from rrcache.model.levels import VISIBLE_FLIP

    if any(s.visible_artifacts and getattr(s, "measured_flip", None) is not None for s in prof.selections):
        return f"mean FLIP ≥ {VISIBLE_FLIP:g} as measured (below {VISIBLE_DB:.0f} dB PSNR where only predicted)"
    return f"below {VISIBLE_DB:.0f} dB PSNR (predicted)"

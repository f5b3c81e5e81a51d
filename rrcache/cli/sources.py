"""The first argument of ``rrcache render`` and ``rrcache instance``: a shader file or a profile.

A profile folder (the folder ``rrcache profile`` wrote, or its ``profile.json``) stands for the
shader, the session, the defines, the include folders and the vertex shader it was profiled
with, and for its choices: ``--level eN`` takes a level's choice with every option the profile
chose (:mod:`rrcache.choice`), and ``--node`` defaults to the profile's algorithm and
cache options instead of the commands' own defaults.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import click
from click.core import ParameterSource

from rrcache.profiles.document import JSON_NAME


@dataclass
class Source:
    """What the first argument names: ``prof`` (a loaded profile, or None) and the shader,
    session, defines, include folders and vertex shader to load."""

    prof: object
    shader: str
    session: Optional[str]
    defines: dict = field(default_factory=dict)
    include_dirs: tuple = ()
    vertex: Optional[str] = None

    def prepare(self, loaded):
        """The shader prepared for the loaded session ``loaded`` (with these defines, include
        folders and vertex shader): :func:`rrcache.compiler.prepared.prepare_file`."""
        from rrcache.compiler.prepared import prepare_file
        from rrcache.pipeline import all_include_dirs

        return prepare_file(self.shader, loaded, self.defines, all_include_dirs(self.include_dirs, loaded),
                            vertex=self.vertex)


def is_profile(path) -> bool:
    """Whether ``path`` is a profile folder (with ``profile.json``) or a ``profile.json``."""
    p = Path(path)
    return (p.is_dir() and (p / JSON_NAME).is_file()) or (p.name == JSON_NAME and p.is_file())


def resolve(ctx: click.Context, first: str, session: Optional[str], defines: dict, include_dirs, vertex,
            session_required: bool, session_name: str = "SESSION") -> Source:
    """The :class:`Source` of a command's first argument ``first`` (and its SESSION, -D, -I and
    --vert): a profile brings all of them, so giving a SESSION, -D or --vert beside one is a
    usage error (``-I`` adds include folders, as for ``rrcache select``)."""
    if is_profile(first):
        from rrcache.profiles.document import load_profile

        for name, given in ((session_name, session is not None), ("-D", bool(defines)), ("--vert", vertex is not None)):
            if given:
                raise click.UsageError(f"{first} is a profile: it names its shader, session, defines and vertex "
                                       f"shader itself; leave out {name}")
        prof = load_profile(first)
        return Source(prof, prof.shader, prof.session, dict(prof.defines),
                      tuple(include_dirs or ()) + tuple(prof.include_dirs), prof.vertex)
    if Path(first).is_dir():
        raise click.BadParameter(f"{first} is a folder without a {JSON_NAME}: give a shader file or a profile "
                                 "folder ('rrcache profile' writes one)", param_hint="SHADER|PROFILE")
    if session is None and session_required:
        raise click.UsageError("give SHADER SESSION, or a PROFILE folder (which names both)")
    return Source(None, first, session, dict(defines), tuple(include_dirs or ()), vertex)


def given(ctx: click.Context, name: str) -> bool:
    """Whether the option ``name`` (its parameter name) was given on the command line."""
    source = ctx.get_parameter_source(name)
    return source is not None and source not in (ParameterSource.DEFAULT, ParameterSource.DEFAULT_MAP)


def refuse_with_level(ctx: click.Context, names: dict) -> None:
    """With ``--level`` every cache option comes from the profile's choice: a usage error for
    any of ``names`` (parameter name → option as typed) given beside it."""
    for param, option in names.items():
        if given(ctx, param):
            raise click.UsageError(f"--level takes the level's choice with every option the profile chose; leave "
                                   f"out {option} (or give --node to try another choice)")


def describe_selection(prof, sel) -> str:
    """A level's choice in words, the node texts next to the ids: 'cache n74 (turbulence(p))
    every Δn = 12 frames'."""
    if sel.kind == "amortize":
        p = sel.parts[0]
        return (f"amortize {p.estimator} ({p.text or 'its loop'}): {p.samples} of "
                f"{prof.estimator(p.estimator).samples} terms per frame, λ = {p.blend:g}, {p.history} history")
    if not sel.parts:
        return "keep the original shader"
    return " + ".join(f"cache {p.node} ({p.text or prof.node(p.node).text}) every Δn = {p.period} frames"
                      + (f", adaptive: threshold {p.threshold:g}, fast period {p.fast_period}"
                         if p.KIND == "adaptive" else "") for p in sel.parts)

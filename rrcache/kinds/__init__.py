"""The kinds of choice: one module per kind, one registry, one compile cache.

A kind of choice (one cached node, several nodes, an amortized loop, adaptive refresh, …) is one
module of this package holding a :class:`~rrcache.kinds.base.Kind` as ``KIND``: its part, its
variant spec, how it compiles, the runs its training plans, its store tables and how it is shown
(:mod:`rrcache.kinds.base`). The registry finds every module here (a new kind is one new module
plus its tests; a kind defined elsewhere, a plug-in or a test's, joins with :func:`register`), and
every other module asks it instead of testing the kind:

- :func:`kind_of` (a selection or its parts → its :class:`Kind`; None for the original shader),
  :func:`get` (by name), :func:`all_kinds`;
- :func:`parts_from_json` / :func:`parts_to_json` (the parts of ``profile.json`` and the store);
- :func:`spec_for` (a selection → its :class:`~rrcache.runtime.spec.VariantSpec`) and
  :func:`compile` (a spec → its compiled variant, cached by (shader, compiled spec): a profile
  compiles each variant once; :func:`compile_counts` says how often each was compiled).

>>> from rrcache.kinds.single import CachedNode
>>> kind_of((CachedNode("n12", 16),)).name, kind_of((CachedNode("n1", 4), CachedNode("n2", 8))).name
('cache', 'nodes')
>>> spec_for((CachedNode("n12", 16),), "two-pass")
VariantSpec(kind='cache', nodes=('n12',), algorithm='two-pass', filter='bilinear', payload='f4', pack_depth=False, estimator=None, samples=0, history='blend', phase='frame', periods=(16,), block=4, refresh='random', depth_epsilon=0.001, threshold=None, fast_period=4, spread=0.0, blend=0.0)
>>> sorted(k.name for k in all_kinds())[:4]
['adaptive', 'amortize', 'cache', 'nodes']
"""
from __future__ import annotations

import dataclasses
import importlib
import pkgutil
import threading
from collections import Counter, OrderedDict
from typing import Optional

from rrcache.errors import RRCacheError
from rrcache.kinds.base import Kind
from rrcache.runtime.spec import VariantSpec

__all__ = ["Kind", "register", "get", "all_kinds", "kind_of", "part_class", "parts_from_json", "parts_to_json",
           "spec_for", "compile", "compile_counts", "clear_compile_cache"]

_KINDS: dict[str, Kind] = {}
_found = False
_lock = threading.RLock()


def _discover() -> None:
    """Import every module of this package once and register its ``KIND``."""
    global _found
    with _lock:
        if _found:
            return
        for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
            if info.name == "base":
                continue
            module = importlib.import_module(f"{__name__}.{info.name}")
            kind = getattr(module, "KIND", None)
            if isinstance(kind, Kind):
                _KINDS.setdefault(kind.name, kind)
        _found = True


def register(kind: Kind) -> Kind:
    """Add ``kind`` to the registry (a kind defined outside this package); ValueError when its
    name or its part's tag is taken by another kind."""
    _discover()
    with _lock:
        if kind.name in _KINDS and _KINDS[kind.name] is not kind:
            raise ValueError(f"a kind named {kind.name!r} is registered already")
        tags = {k.part.KIND: k for k in _KINDS.values() if k.part is not None}
        if kind.part is not None and kind.part.KIND in tags and tags[kind.part.KIND] is not kind:
            raise ValueError(f"part tag {kind.part.KIND!r} belongs to the kind {tags[kind.part.KIND].name!r}")
        _KINDS[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Take a kind added with :func:`register` out again (tests)."""
    with _lock:
        _KINDS.pop(name, None)


def all_kinds() -> list[Kind]:
    """Every registered kind, by name."""
    _discover()
    return [_KINDS[n] for n in sorted(_KINDS)]


def get(name: str) -> Kind:
    """The kind called ``name``; RRCacheError naming the known ones."""
    _discover()
    try:
        return _KINDS[name]
    except KeyError:
        raise RRCacheError(f"no kind of choice is called {name!r} (known: {', '.join(sorted(_KINDS))})",
                           "kind") from None


def kind_of(choice) -> Optional[Kind]:
    """The kind of a selection (or of its parts); None for the original shader (no part). A
    combination no kind claims raises RRCacheError."""
    parts = tuple(getattr(choice, "parts", choice))
    if not parts:
        return None
    for kind in all_kinds():
        if kind.claims(parts):
            return kind
    raise RRCacheError("no kind of choice caches " + " + ".join(p.KIND for p in parts), "selection",
                       hint="a new kind of choice is a module of rrcache.kinds")


def part_class(tag: str) -> Optional[type]:
    """The part class whose JSON ``kind`` tag is ``tag`` (None when no kind owns it)."""
    for kind in all_kinds():
        if kind.part is not None and kind.part.KIND == tag:
            return kind.part
    return None


#: fields whose default value is left out of a part's JSON (added after documents were written with
#: their default behaviour)
_DEFAULT_FIELDS = {("filter", "bilinear"), ("payload", "f4")}


def parts_to_json(parts) -> list:
    """The parts as JSON objects, each with its ``kind`` tag first."""
    return [{"kind": p.KIND, **{k: v for k, v in dataclasses.asdict(p).items() if (k, v) not in _DEFAULT_FIELDS}}
            for p in parts]


def parts_from_json(data, where: str) -> tuple:
    """The parts of :func:`parts_to_json`'s list; RRCacheError naming ``where[i]`` and the key
    for anything else."""
    if not isinstance(data, list):
        raise RRCacheError("must be a list of parts", where)
    out = []
    for i, item in enumerate(data):
        at = f"{where}[{i}]"
        if not isinstance(item, dict):
            raise RRCacheError("must be an object with a 'kind'", at)
        cls = part_class(item.get("kind"))
        if cls is None:
            known = ", ".join(k.part.KIND for k in all_kinds() if k.part is not None)
            raise RRCacheError(f"unknown kind {item.get('kind')!r} (known: {known})", f"{at}.kind")
        out.append(cls.from_json(item, at))
    return tuple(out)


def spec_for(choice, algorithm: Optional[str] = None, filter: Optional[str] = None, **runtime) -> VariantSpec:
    """The :class:`VariantSpec` of a selection (or of its parts) run with ``algorithm`` (default:
    the selection's, else three-pass), the profile's cache ``filter`` (None: the default) and the
    runtime's fields ``runtime`` (``block``, ``refresh``, ``depth_epsilon``). The original
    shader has none: RRCacheError."""
    kind = kind_of(choice)
    if kind is None:
        raise RRCacheError("the original shader has no variant", "selection",
                           hint="the original shader needs none; rrcache.choice.write writes its files")
    algorithm = algorithm or getattr(choice, "algorithm", None) or "three-pass"
    return kind.spec(tuple(getattr(choice, "parts", choice)), algorithm, filter, **runtime)


class CompileCache:
    """Compiled variants keyed by (the shader's hash and analysis, the compiled part of the spec):
    one compilation per variant however often it is run, validated, written or shown. Each
    caller gets the cached passes bound to its own spec (periods, threshold, blend). Holds at
    most ``size`` variants (least recently used dropped)."""

    def __init__(self, size: int = 256):
        self.size = size
        self._items: OrderedDict = OrderedDict()
        #: compiled spec -> how many times it was compiled (a cache hit counts nothing)
        self.counts: Counter = Counter()
        self.hits = 0
        self._lock = threading.RLock()

    @staticmethod
    def key(work, spec: VariantSpec) -> tuple:
        """(shader hash, its file and its vertex shader's, unroll limit, sum order, compiled spec):
        the hash covers what is compiled, the paths what the variant names (its manifest, its
        messages), the analysis settings the node ids; a work without a hash is its own key."""
        shader = getattr(work, "hash", None)
        if not shader:
            return ("object", id(work), spec.compiled())
        paths = (str(getattr(work.shader, "path", None)), str(getattr(getattr(work, "vertex", None), "path", None)))
        scores = getattr(work, "term_scores", None) or {}
        order = tuple(sorted((str(k), repr(v)) for k, v in dict(scores).items()))
        return (shader, *paths, getattr(work, "max_unroll", None), order, spec.compiled())

    def get(self, work, spec: VariantSpec):
        key = self.key(work, spec)
        with self._lock:
            found = self._items.get(key)
            if found is not None:
                self._items.move_to_end(key)
                self.hits += 1
        if found is None:
            found = get(spec.kind).compile(work, spec)
            with self._lock:
                self.counts[spec.compiled()] += 1
                self._items[key] = found
                while len(self._items) > self.size:
                    self._items.popitem(last=False)
        return _bound(found, spec)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
            self.counts.clear()
            self.hits = 0


def _bound(variant, spec: VariantSpec):
    """The cached ``variant``'s passes with ``spec`` as its spec (and an amortized loop's λ)."""
    changes = {"spec": spec}
    if variant.amortized is not None:
        changes["amortized"] = dict(variant.amortized, **{"lambda": float(spec.blend)})
    return dataclasses.replace(variant, **changes)


#: the process's compile cache (a profile, its validation, its files and its report share it)
CACHE = CompileCache()


def compile(work, spec: VariantSpec):
    """The compiled variant of ``spec`` over ``work`` (a :class:`~rrcache.pipeline.ShaderWork`),
    from :data:`CACHE` when it holds it (see :class:`CompileCache`)."""
    return CACHE.get(work, spec)


def compile_counts() -> Counter:
    """Compiled spec → how many times it was compiled since the cache was last cleared."""
    return Counter(CACHE.counts)


def clear_compile_cache() -> None:
    CACHE.clear()

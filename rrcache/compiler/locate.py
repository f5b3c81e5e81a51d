"""Pass: find the cached node E and the statement S of ``main`` that contains it.

:func:`prepare` takes the analysed (inlined, unrolled) shader and a node id and returns a
:class:`Located`: a ``#version 330 core`` copy of the unit (through
:func:`rrcache.glsl.legacy.to_core`) in which E has been replaced by the placeholder identifier
:data:`PLACEHOLDER`, and E itself (converted to core the same way) kept aside. Every pass
starts from a copy of that unit and puts its own expression where the placeholder is.

:func:`find_site` finds S in such a copy: the innermost statement whose *own* expressions (not
its sub-statements) hold the placeholder, made the element of a ``{ ... }`` block so that code
can be inserted right before and after it.

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("varying vec2 v_texcoord;\\n"
...                  "void main() { float a = sin(v_texcoord.x); gl_FragColor = vec4(a * 2.0); }")
>>> node = [n for n in s.unit.walk() if isinstance(n, A.Call) and n.name == "sin"][0]
>>> loc = prepare(s, node)
>>> loc.type_name, loc.text
('float', 'sin(v_texcoord.x)')
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any, Optional, Union

from rrcache.errors import SourceLoc, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.legacy import to_core
from rrcache.glsl.printer import print_expr
from rrcache.glsl.ast import branches, contains, is_ident, main_function, own_parts, substitute, walk

#: The identifier standing for E in the prepared unit (never printed).
PLACEHOLDER = "rr_cachedNodePlaceholder"
_CARRIER = "rr_cachedNodeCarrier"

#: GLSL types a node may have, with their component counts.
NODE_TYPES = {"float": 1, "vec2": 2, "vec3": 3, "vec4": 4}


@dataclass
class Located:
    """The cached node, ready for the passes.

    ``unit`` is the core-profile unit with E replaced by :data:`PLACEHOLDER`; ``expr`` is E (core
    profile; clone it before inserting it anywhere); ``type_name`` its GLSL type, ``components``
    its size, ``text`` E as printed from the analysed shader, ``loc`` its place, ``path`` the
    shader's file (for messages).
    """

    unit: A.TranslationUnit
    expr: A.Expr
    type_name: str
    components: int
    text: str
    loc: Optional[SourceLoc]
    path: str


@dataclass
class Site:
    """Where S sits: ``block.stmts[index] is stmt``."""

    block: A.Compound
    index: int
    stmt: A.Stmt


def analysed_unit(analysed: Any) -> A.TranslationUnit:
    """The translation unit of whatever the analysis returned (a Shader, something holding a
    ``shader``, or a unit)."""
    if isinstance(analysed, A.TranslationUnit):
        return analysed
    unit = getattr(analysed, "unit", None)
    if isinstance(unit, A.TranslationUnit):
        return unit
    shader = getattr(analysed, "shader", None)
    if shader is not None and isinstance(getattr(shader, "unit", None), A.TranslationUnit):
        return shader.unit
    raise TypeError(f"expected an analysed shader or a translation unit, not {type(analysed).__name__}")


def _shader_path(analysed: Any) -> str:
    for obj in (analysed, getattr(analysed, "shader", None)):
        path = getattr(obj, "path", None)
        if isinstance(path, str):
            return path
    return "<shader>"


def resolve(analysed: Any, node_id: Union[str, int, A.Expr]) -> A.Expr:
    """The expression node ``node_id`` names in the analysed shader: an id of the analysis' node
    table (``"n42"``; an int ``42`` means the same), or an expression node of the unit itself.
    Unknown ids raise :class:`~rrcache.errors.RRCacheError` (from
    :func:`rrcache.analysis.find_node`)."""
    if isinstance(node_id, A.Expr):
        return node_id
    if isinstance(node_id, bool) or not isinstance(node_id, (int, str)):
        raise TypeError(f"node id must be a str like 'n42' or an expression node, "
                        f"not {type(node_id).__name__}")
    from rrcache.analysis.cacheable import find_node

    target = analysed if isinstance(analysed, A.TranslationUnit) else getattr(analysed, "shader", analysed)
    return find_node(target, node_id if isinstance(node_id, str) else f"n{node_id}")


def _replace_by_identity(root: A.Node, target: A.Node, new: A.Node) -> bool:
    return substitute(root, lambda n: n is target, lambda n: new) == 1


def prepare(analysed: Any, node_id: Union[int, A.Expr]) -> Located:
    """Locate E in the analysed shader and build the placeholder unit (see the module doc)."""
    unit = analysed_unit(analysed)
    path = _shader_path(analysed)
    node = resolve(analysed, node_id)
    t = getattr(node, "type", None)
    name = t.glsl_name() if t is not None else None
    if name not in NODE_TYPES:
        raise UnsupportedShaderError(
            f"node '{print_expr(node)}' has type {name or 'unknown'}; only float and vec2-4 values "
            "are cached", node.loc, "pick a float or vector node from the node table")
    main = main_function(unit)
    if main is None or not any(n is node for n in walk(main.body)):
        raise UnsupportedShaderError(
            f"node '{print_expr(node)}' is not in main() of the analysed shader", node.loc,
            "pass the shader returned by the analysis and a node id from its table")
    memo: dict[int, Any] = {}
    work = copy.deepcopy(unit, memo)
    e_copy = memo[id(node)]
    work_main = main_function(work)
    if not _replace_by_identity(work_main.body, e_copy, A.Ident(PLACEHOLDER, loc=node.loc)):
        raise UnsupportedShaderError("the cached node occurs more than once in the tree", node.loc)
    # E rides along in a statement of main so that to_core rewrites it with the same renames.
    work_main.body.stmts.append(A.ExprStmt(A.Sequence([A.Ident(_CARRIER), e_copy])))
    core = to_core(work)
    core_main = main_function(core)
    carrier = core_main.body.stmts.pop()
    assert isinstance(carrier, A.ExprStmt) and isinstance(carrier.expr, A.Sequence)
    expr = carrier.expr.exprs[1]
    return Located(core, expr, name, NODE_TYPES[name], print_expr(node), node.loc, path)


def find_site(unit: A.TranslationUnit, name: str = PLACEHOLDER) -> Site:
    """Find S, the statement of main holding the identifier ``name`` in its own expressions.

    A statement that is the bare body of an ``if``/loop is first wrapped into a block. The
    placeholder in a loop condition or step (evaluated once per iteration) is refused.
    """
    main = main_function(unit)
    pred = is_ident(name)

    def search(block: A.Compound) -> Optional[Site]:
        for i, s in enumerate(block.stmts):
            if isinstance(s, A.Compound):
                found = search(s)
                if found:
                    return found
                continue
            if any(contains(p, pred) for p in own_parts(s)):
                if (isinstance(s, (A.For, A.While, A.DoWhile))
                        and not (isinstance(s, A.For) and contains(s.init, pred))):
                    raise UnsupportedShaderError(
                        "the cached node is in a loop condition or step", s.loc,
                        "nodes evaluated once per loop iteration are dynamic; pick another")
                return Site(block, i, s)
            for field_name, sub in branches(s):
                if not contains(sub, pred):
                    continue
                if not isinstance(sub, A.Compound):
                    sub = A.Compound([sub], loc=sub.loc)
                    setattr(s, field_name, sub)
                return search(sub)
        return None

    site = search(main.body) if main is not None else None
    if site is None:
        raise UnsupportedShaderError("the cached node was lost while preparing the passes", None,
                                     "this is a bug in rrcache; please report it")
    return site

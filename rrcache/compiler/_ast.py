"""Tree helpers shared by the compiler passes (not a pass itself).

The walkers here are those of :mod:`rrcache.analysis._tree` with declaration types followed
(struct type names and array sizes live there); like those they never follow the semantic
annotations (``Expr.type``, ``Ident.symbol``, ``Call.target``, ``Call.kind``), so a walk never
wanders into another function's body.

>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("void main() { float x = 1.0; x = x + 2.0; }")
>>> sum(1 for n in walk(unit) if isinstance(n, A.Ident))
2
"""
from __future__ import annotations

from typing import Callable, Iterator, Optional

from rrcache.analysis import _tree as tree
from rrcache.glsl import ast as A


def tree_fields(cls: type) -> tuple[str, ...]:
    """The names of the syntax fields of an AST class, declaration types included."""
    return tree.tree_fields(cls, decl_types=True)


def children(node: A.Node) -> Iterator[A.Node]:
    """Direct syntax children in source order, declaration types included."""
    return tree.children(node, decl_types=True)


def walk(node: A.Node) -> Iterator[A.Node]:
    """``node`` and its syntax descendants, pre-order (iterative), declaration types included."""
    return tree.walk(node, decl_types=True)


def post_order(node: A.Node) -> Iterator[A.Node]:
    """``node`` and its descendants, children (left to right) before their parent: the order
    in which an expression's operands are evaluated."""
    for child in children(node):
        yield from post_order(child)
    yield node


def substitute(node: A.Node, pred: Callable[[A.Node], bool],
               make: Callable[[A.Node], A.Node]) -> int:
    """Replace, in place, every descendant ``n`` of ``node`` with ``pred(n)`` true by
    ``make(n)`` (the replacement is not searched again). Returns the number replaced."""
    count = 0
    for name in tree_fields(type(node)):
        value = getattr(node, name)
        if isinstance(value, A.Node):
            if pred(value):
                setattr(node, name, make(value))
                count += 1
            else:
                count += substitute(value, pred, make)
        elif isinstance(value, list):
            for i, item in enumerate(value):
                if isinstance(item, A.Node):
                    if pred(item):
                        value[i] = make(item)
                        count += 1
                    else:
                        count += substitute(item, pred, make)
                elif isinstance(item, tuple):
                    new = []
                    for sub in item:
                        if isinstance(sub, A.Node) and pred(sub):
                            new.append(make(sub))
                            count += 1
                        else:
                            if isinstance(sub, A.Node):
                                count += substitute(sub, pred, make)
                            new.append(sub)
                    value[i] = tuple(new)
    return count


def is_ident(name: str) -> Callable[[A.Node], bool]:
    """A predicate: the node is the identifier ``name``."""
    return lambda n: isinstance(n, A.Ident) and n.name == name


def contains(node: Optional[A.Node], pred: Callable[[A.Node], bool]) -> bool:
    """Whether ``node`` or a descendant satisfies ``pred``."""
    return node is not None and any(pred(n) for n in walk(node))


def main_function(unit: A.TranslationUnit) -> Optional[A.FunctionDecl]:
    """The definition of ``void main()``, or None."""
    for d in unit.decls:
        if isinstance(d, A.FunctionDecl) and d.name == "main" and d.body is not None:
            return d
    return None

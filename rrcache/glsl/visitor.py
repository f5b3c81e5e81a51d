"""The one visitor of the GLSL tree, as pycparser's ``c_ast.NodeVisitor``.

:meth:`NodeVisitor.visit` dispatches on the node's class to the method ``visit_<ClassName>``
(the first found along the class's bases: ``visit_Expr`` takes every expression no more specific
method takes, ``visit_Stmt`` every statement, ``visit_Node`` anything), and to
:meth:`~NodeVisitor.generic_visit` when there is none, which visits the node's syntax children
in source order. The children come from the tree's one spec (:func:`rrcache.glsl.ast.children`:
the fields of the node classes), so a pass overrides only the classes it cares about and a new
node class needs no audit of hand-written ladders. Extra positional arguments of ``visit`` (a
context, a scope) are passed on to the method and, by ``generic_visit``, to the children.

:class:`NodeTransformer` rewrites: its ``generic_visit`` replaces every child by what visiting
it returns (None removes an item from a list, a list returned for an item of a list is spliced
in, as Python's ``ast.NodeTransformer`` does) and returns the node.

>>> from rrcache.glsl import ast as A
>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("void main() { float x = a * b + c; x = sin(x); }")
>>> class Names(NodeVisitor):
...     def __init__(self):
...         self.names = []
...     def visit_Ident(self, node):
...         self.names.append(node.name)
...     def visit_Call(self, node):
...         self.names.append(node.name + "()")
...         self.generic_visit(node)
>>> v = Names(); v.visit(unit); v.names
['a', 'b', 'c', 'x', 'sin()', 'x']
>>> class Squares(NodeTransformer):
...     def visit_Ident(self, node):
...         return A.Binary("*", node, A.Ident(node.name)) if node.name == "a" else node
>>> from rrcache.glsl.printer import print_glsl
>>> print(print_glsl(Squares().visit(unit)).splitlines()[2].strip())
float x = a * a * b + c;
"""
from __future__ import annotations

from typing import Any, Callable

from rrcache.glsl.ast import Node, child_fields, children

__all__ = ["NodeVisitor", "NodeTransformer"]


class NodeVisitor:
    """Dispatch on the node class to ``visit_<ClassName>``; :meth:`generic_visit` otherwise.

    ``decl_types`` (a class attribute): whether the generic descent enters the ``FullType`` of
    declarations (:data:`rrcache.glsl.ast.DECL_TYPE`).
    """

    decl_types = True
    _dispatch: dict[type, Callable] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls._dispatch = {}   # node class -> the method visiting it, filled on first use

    @classmethod
    def method_for(cls, node_cls: type) -> Callable:
        """The (unbound) method visiting nodes of class ``node_cls``."""
        found = cls._dispatch.get(node_cls)
        if found is None:
            for k in node_cls.__mro__:
                found = getattr(cls, "visit_" + k.__name__, None)
                if found is not None:
                    break
            else:
                found = cls.generic_visit
            cls._dispatch[node_cls] = found
        return found

    def visit(self, node: Node, *args: Any) -> Any:
        """Visit ``node`` with the method for its class; returns what the method returns."""
        method = self._dispatch.get(node.__class__)
        if method is None:
            method = self.method_for(node.__class__)
        return method(self, node, *args)

    def generic_visit(self, node: Node, *args: Any) -> Any:
        """Visit the syntax children of ``node`` in source order."""
        for child in children(node, self.decl_types):
            self.visit(child, *args)
        return None


class NodeTransformer(NodeVisitor):
    """A visitor whose :meth:`generic_visit` replaces each child by what visiting it returns."""

    def generic_visit(self, node: Node, *args: Any) -> Any:
        d = node.__dict__
        node_cls = Node
        for name in child_fields(node.__class__, self.decl_types):
            value = d[name]
            if value is None:
                continue
            if isinstance(value, node_cls):
                d[name] = self.visit(value, *args)
            elif value.__class__ is list:
                new = []
                for item in value:
                    if isinstance(item, node_cls):
                        item = self.visit(item, *args)
                        if item is None:
                            continue
                        if item.__class__ is list:
                            new.extend(item)
                            continue
                    elif item.__class__ is tuple:
                        item = tuple(self.visit(x, *args) if isinstance(x, node_cls) else x
                                     for x in item)
                    new.append(item)
                d[name] = new
        return node

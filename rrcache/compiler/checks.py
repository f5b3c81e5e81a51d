"""Whether a node can be cached with an algorithm: the node table's word, asked by every entry
of the compiler (:func:`rrcache.compiler.instance`, :func:`rrcache.compiler.instance_nodes`)."""
from __future__ import annotations

from typing import Any, Union

from rrcache.errors import UnsupportedShaderError
from rrcache.glsl import ast as A


def check_algorithm(analysed: Any, node_id: Union[int, str, A.Expr], algorithm: str) -> None:
    """Raise :class:`UnsupportedShaderError` when ``analysed`` is a node table whose entry for
    ``node_id`` is not valid for ``algorithm`` (a node that needs screen-space derivatives
    cannot be cached by one-pass), naming the reason and the algorithms that can."""
    for n in getattr(analysed, "nodes", None) or ():
        if (n.id == node_id or n.node is node_id) and algorithm in getattr(n, "invalid", {}):
            valid = getattr(n, "algorithms", [])
            raise UnsupportedShaderError(
                f"node {n.id} '{n.text}' cannot be cached with {algorithm}: "
                f"{n.invalid[algorithm]}", n.node.loc,
                f"use --algorithm {' or '.join(valid)}" if valid else "pick another node")

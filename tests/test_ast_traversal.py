"""The one traversal of the syntax tree (``rrcache.glsl.ast``), its users, and the module rule
that no module imports another package's private module."""
from __future__ import annotations

import ast as pyast
from dataclasses import fields
from pathlib import Path

import pytest

from rrcache.compiler.hoist import hoist, side_effect_before
from rrcache.compiler.locate import PLACEHOLDER, find_site
from rrcache.glsl import ast as A
from rrcache.glsl.frontend import parse_shader
from rrcache.glsl.parser import parse_source
from rrcache.glsl.printer import print_glsl
from rrcache.glsl.rewrite import clone

ROOT = Path(__file__).resolve().parents[1]
CORPUS = sorted((ROOT / "tests" / "glsl" / "corpus").glob("*.frag"))
ANNOTATIONS = {"loc", "symbol", "text", "version_loc", "extension_locs"}


def reachable(node, decl_types=True):
    """Every node reachable through dataclass fields other than the semantic annotations: what
    the spec-driven walk must visit, found without the spec."""
    seen, stack = [], [node]
    while stack:
        n = stack.pop()
        seen.append(n)
        for f in fields(n):
            if f.name in ANNOTATIONS or (f.name == "type" and isinstance(n, A.Expr)) \
                    or (f.name in ("target", "kind") and isinstance(n, A.Call)):
                continue
            if f.name == "type" and not decl_types:
                continue
            value, found = getattr(n, f.name), []
            for item in value if isinstance(value, list) else [value]:
                for sub in item if isinstance(item, tuple) else (item,):
                    if isinstance(sub, A.Node):
                        found.append(sub)
            stack.extend(found)
    return seen


@pytest.mark.parametrize("path", CORPUS[::4], ids=lambda p: p.stem)
def test_walk_visits_every_syntax_node_once_and_never_a_call_target(path):
    shader = parse_shader(path.read_text(), path.name)
    unit = shader.unit
    for decl_types in (True, False):
        walked = list(A.walk(unit, decl_types=decl_types))
        assert len({id(n) for n in walked}) == len(walked)
        assert {id(n) for n in walked} == {id(n) for n in reachable(unit, decl_types)}
    assert sum(isinstance(n, A.FunctionDecl) for n in A.walk(unit)) == \
        sum(isinstance(d, A.FunctionDecl) for d in unit.decls)
    assert list(unit.walk()) == list(A.walk(unit))


def test_pre_order_and_post_order():
    e = parse_source("void main() { x = a * (b + c); }").decls[0].body.stmts[0].expr
    names = lambda nodes: [n.name if isinstance(n, A.Ident) else type(n).__name__ for n in nodes]
    assert names(A.walk(e)) == ["Assign", "x", "Binary", "a", "Binary", "b", "c"]
    assert names(A.post_order(e)) == ["x", "a", "b", "c", "Binary", "Binary", "Assign"]


def test_declaration_types_are_marked_in_the_classes():
    marked = {(cls.__name__, f.name) for cls in (A.VariableDecl, A.Param, A.StructMember, A.FunctionDecl)
              for f in fields(cls) if f.metadata.get("decl_type")}
    assert marked == {("VariableDecl", "type"), ("Param", "type"), ("StructMember", "type")}
    assert A.child_fields(A.Call) == ("args", "array_dims")  # never target or kind


def test_clone_follows_the_spec_and_shares_declaration_types():
    unit = parse_shader("uniform vec2 u[2];\nvoid main() { float a[2] = float[2](u[0].x, 1.0);"
                        " gl_FragColor = vec4(a[1]); }").unit
    copy = clone(unit)
    assert copy == unit and print_glsl(copy) == print_glsl(unit)
    originals = {id(n) for n in A.walk(unit, decl_types=False)}
    assert not originals & {id(n) for n in A.walk(copy, decl_types=False)}
    assert copy.decls[0].type is unit.decls[0].type


def test_own_parts_of_a_for_loop_in_evaluation_order():
    loop = parse_source("void main() { for (int i = 0; i < 3; i++) { x += 1.0; } }").decls[0].body.stmts[0]
    assert A.own_parts(loop) == [loop.init, loop.cond, loop.step]
    assert A.branches(loop) == [("body", loop.body)]


def _site(src):
    unit = parse_source(src)
    return unit, find_site(unit)


def test_hoist_and_locate_agree_on_a_for_init():
    # the placeholder in a for-init: located there, and the step's i++ (evaluated after the
    # init) does not force the inline form
    unit, site = _site(f"void main() {{ for (float t = 2.0 * {PLACEHOLDER}; t < 4.0; t += 1.0) {{ }} }}")
    assert isinstance(site.stmt, A.For)
    assert not side_effect_before(site.stmt)
    assert hoist(site, "float", A.Call("sin", [A.Ident("x")])) == "hoist"
    text = print_glsl(unit)
    assert text.index("float rr_node = sin(x);") < text.index("for (float t = 2.0 * rr_node;")
    # an effect in the init before the placeholder: inline form
    unit, site = _site(f"void main() {{ float k = 0.0; for (float t = (k += 1.0) * {PLACEHOLDER}; t < 4.0; t++) {{ }} }}")
    assert side_effect_before(site.stmt)
    assert hoist(site, "float", A.Call("sin", [A.Ident("x")])) == "inline"


def test_locate_refuses_a_node_in_a_loop_condition_or_step():
    from rrcache.errors import UnsupportedShaderError

    for src in (f"void main() {{ for (int i = 0; float(i) < {PLACEHOLDER}; i++) {{ }} }}",
                f"void main() {{ for (float t = 0.0; t < 4.0; t += {PLACEHOLDER}) {{ }} }}",
                f"void main() {{ while ({PLACEHOLDER} > 0.0) {{ }} }}"):
        with pytest.raises(UnsupportedShaderError, match="loop condition or step"):
            find_site(parse_source(src))


def _imports(path: Path):
    tree = pyast.parse(path.read_text(), str(path))
    for node in pyast.walk(tree):
        if isinstance(node, pyast.ImportFrom) and node.module and node.level == 0:
            yield node.module, [a.name for a in node.names]
        elif isinstance(node, pyast.Import):
            for a in node.names:
                yield a.name, []


def test_no_module_imports_another_packages_private_module():
    bad = []
    for path in sorted((ROOT / "rrcache").rglob("*.py")):
        package = ".".join(path.relative_to(ROOT).parent.parts)
        for module, names in _imports(path):
            if not module.startswith("rrcache"):
                continue
            parts = module.split(".")
            for k, part in enumerate(parts):
                if part.startswith("_") and not part.startswith("__"):
                    if ".".join(parts[:k]) != package:
                        bad.append(f"{path.relative_to(ROOT)}: {module}")
            for name in names:
                if name.startswith("_") and (ROOT / Path(*parts) / f"{name}.py").exists() \
                        and module != package:
                    bad.append(f"{path.relative_to(ROOT)}: {module}.{name}")
    assert not bad, bad

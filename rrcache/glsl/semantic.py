"""Semantic analysis of a parsed fragment shader: scopes, name resolution and type checking.

:func:`check` walks a :class:`~rrcache.glsl.ast.TranslationUnit` once, in source order. It
resolves every name (``Ident.symbol``), types every expression (``Expr.type``), resolves every call
to a user function, a built-in or a constructor (``Call.kind``/``Call.target``) with the implicit
conversions the shader's version allows, folds integer constant expressions (array sizes), checks
assignments (l-values, read-only variables), returns, ``break``/``continue``, and rejects
recursion. It stops at the first error with exactly one :class:`~rrcache.errors.SemanticError`
carrying the file:line:col and, where it helps, a hint.

>>> from rrcache.glsl.parser import parse_source
>>> unit = parse_source("#version 330\\nuniform float u_time;\\nout vec4 c;\\n"
...                     "void main() { c = vec4(sin(u_time)); }")
>>> info = check(unit)
>>> list(info.uniforms), info.outputs["c"].type
(['u_time'], Type('vec4'))
"""
from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from typing import Any, Optional, Union

from rrcache.errors import SemanticError, SourceLoc
from rrcache.glsl import ast as A
from rrcache.glsl.visitor import NodeVisitor
from rrcache.glsl.builtins import BUILTIN_VARIABLES, BuiltinFunction
from rrcache.glsl.builtins import lookup as builtin_lookup
from rrcache.glsl.constfold import const_value
from rrcache.glsl.lexer import is_keyword
from rrcache.glsl.types import (BOOL, DOUBLE, FLOAT, FLOAT16, INT, INT64, INTEGER_BASES,
                                SOFT_TYPE_NAMES, UINT, UINT64, VOID, Type, swizzle)

__all__ = ["Symbol", "UserFunction", "SemanticInfo", "check", "implicit_conversions"]


@dataclass(eq=False)
class Symbol:
    """A declared name. ``kind`` is ``global``, ``uniform``, ``in``, ``out``, ``const``,
    ``local``, ``param`` or ``builtin``; ``decl`` the declaring node (a ``VariableDecl``,
    ``Param``, ``InterfaceBlock`` or, for built-ins, the ``BuiltinVariable``); ``const_value`` the
    folded value of a scalar constant."""

    name: str
    type: Type
    kind: str
    decl: Any
    loc: Optional[SourceLoc]
    read_only: bool
    qualifiers: tuple = ()
    const_value: Any = None

    def __repr__(self) -> str:
        return f"Symbol({self.name!r}, {self.type}, {self.kind!r})"


def _same_redeclaration(prev: Symbol, sym: Symbol) -> bool:
    """Whether ``sym`` redeclares the already redeclared built-in ``prev`` word for word."""
    return (isinstance(prev.decl, A.VariableDecl) and isinstance(sym.decl, A.VariableDecl)
            and prev.decl.type == sym.decl.type)


@dataclass(eq=False)
class UserFunction:
    """One user-function signature: its prototype and/or definition."""

    name: str
    return_type: Type
    param_types: tuple[Type, ...]
    param_quals: tuple[str, ...]
    prototype: Optional[A.FunctionDecl] = None
    definition: Optional[A.FunctionDecl] = None

    @property
    def decl(self) -> A.FunctionDecl:
        """The definition when there is one, else the prototype."""
        decl = self.definition or self.prototype
        assert decl is not None
        return decl

    @property
    def params(self) -> tuple[Type, ...]:
        return self.param_types

    @property
    def qualifiers(self) -> tuple[str, ...]:
        return self.param_quals

    def signature(self) -> str:
        """``name(type, type)``: the key of :attr:`SemanticInfo.functions`."""
        return f"{self.name}({', '.join(map(str, self.param_types))})"

    def __str__(self) -> str:
        params = ", ".join((f"{q} " if q != "in" else "") + str(t)
                           for q, t in zip(self.param_quals, self.param_types))
        return f"{self.return_type} {self.name}({params})"


@dataclass
class SemanticInfo:
    """What :func:`check` learnt about a shader.

    ``globals`` holds every global variable (in declaration order); ``uniforms``, ``inputs`` and
    ``outputs`` the user-declared ones by storage (interface-block members included, with the
    ``InterfaceBlock`` as ``decl``); ``used_globals`` the names of globals (user or built-in)
    referenced inside a function; ``functions`` maps a signature (``f(vec3, float)``) to its
    :class:`UserFunction`; ``call_graph`` a signature to the signatures it calls; ``builtins_used``
    the names of built-in functions called.
    """

    version: int
    profile: Optional[str]
    es: bool
    globals: dict[str, Symbol] = field(default_factory=dict)
    uniforms: dict[str, Symbol] = field(default_factory=dict)
    inputs: dict[str, Symbol] = field(default_factory=dict)
    outputs: dict[str, Symbol] = field(default_factory=dict)
    structs: dict[str, Type] = field(default_factory=dict)
    functions: dict[str, UserFunction] = field(default_factory=dict)
    call_graph: dict[str, set[str]] = field(default_factory=dict)
    builtins_used: set[str] = field(default_factory=set)
    used_globals: set[str] = field(default_factory=set)
    main: Optional[A.FunctionDecl] = None

    def function_named(self, name: str) -> list[UserFunction]:
        """Every overload of the user function ``name``."""
        return [f for f in self.functions.values() if f.name == name]


# ----------------------------------------------------------------------------- conversions

_CONV_130 = {("int", "float"): 2, ("uint", "float"): 2}
_CONV_400 = {("int", "uint"): 2, ("int", "float"): 2, ("uint", "float"): 2,
             ("float", "double"): 1, ("int", "double"): 3, ("uint", "double"): 3,
             # explicit arithmetic types (GL_ARB_gpu_shader_int64, half floats)
             ("int", "int64_t"): 1, ("uint", "uint64_t"): 1, ("int", "uint64_t"): 2,
             ("int64_t", "uint64_t"): 2, ("int64_t", "double"): 3, ("uint64_t", "double"): 3,
             ("float16_t", "float"): 1, ("float16_t", "double"): 2}


def implicit_conversions(version: int, es: bool) -> dict[tuple[str, str], int]:
    """The implicit base-type conversions a version allows, ``(from, to) -> rank`` (lower ranks
    are preferred in overload resolution): none in GLSL ES and GLSL 1.10, int/uint→float from
    1.20, and int→uint, →double from 4.00.

    >>> implicit_conversions(330, False)[("int", "float")]
    2
    >>> implicit_conversions(300, True)
    {}
    """
    if es or version <= 110:
        return {}
    if version < 400:
        return dict(_CONV_130)
    return dict(_CONV_400)


_ASSIGN_TO_BINARY = {"+=": "+", "-=": "-", "*=": "*", "/=": "/", "%=": "%", "<<=": "<<",
                     ">>=": ">>", "&=": "&", "^=": "^", "|=": "|"}
_STORAGE = {"uniform": "uniform", "in": "in", "varying": "in", "attribute": "in", "out": "out",
            "const": "const", "buffer": "global", "shared": "global"}
_KIND_WORDS = {"uniform": "uniform", "in": "input", "const": "constant",
               "builtin": "read-only built-in variable", "param": "const parameter",
               "global": "read-only variable", "local": "read-only variable"}


class _Scope:
    __slots__ = ("vars", "structs", "parent", "is_global")

    def __init__(self, parent: Optional["_Scope"]):
        self.vars: dict[str, Symbol] = {}
        self.structs: dict[str, Type] = {}
        self.parent = parent
        self.is_global = parent is None


def _err(message: str, node: Any, hint: Optional[str] = None) -> SemanticError:
    return SemanticError(message, getattr(node, "loc", None), hint)


def _qual_words(ftype: A.FullType) -> tuple[str, ...]:
    return tuple(q for q in ftype.qualifiers if isinstance(q, str))


class _Checker(NodeVisitor):
    """Visiting a declaration or statement checks it; visiting an expression (through
    :meth:`expr`, which annotates it) returns its type."""

    def __init__(self, unit: A.TranslationUnit):
        profile = unit.profile
        version = unit.version or (100 if profile == "es" else 110)
        es = profile == "es" or version in (100, 300, 310, 320)
        self.info = SemanticInfo(version, profile, es)
        self.conv = implicit_conversions(version, es)
        # GL_ARB/NV_bindless_texture make samplers and images plain values that can be assigned.
        self.bindless = any(name in ("GL_ARB_bindless_texture", "GL_NV_bindless_texture")
                            and behavior != "disable" for name, behavior in unit.extensions)
        self.scope = _Scope(None)
        self.global_scope = self.scope
        self.by_name: dict[str, list[UserFunction]] = {}
        self.current: Optional[UserFunction] = None
        self.loops = 0
        self.switches: list[set] = []
        self.calls: list[tuple[A.Call, UserFunction]] = []
        self.edge_loc: dict[tuple[str, str], Optional[SourceLoc]] = {}
        self.builtin_symbols: dict[str, Symbol] = {}
        self.overload_cache: dict[tuple, Any] = {}

    # ================================================================== scopes
    def push(self) -> None:
        self.scope = _Scope(self.scope)

    def pop(self) -> None:
        assert self.scope.parent is not None
        self.scope = self.scope.parent

    def lookup(self, name: str) -> Union[Symbol, Type, None]:
        s: Optional[_Scope] = self.scope
        while s is not None:
            sym = s.vars.get(name)
            if sym is not None:
                return sym
            st = s.structs.get(name)
            if st is not None:
                return st
            s = s.parent
        return None

    def _check_new_name(self, name: str, node: Any, what: str) -> None:
        scope = self.scope
        prev = scope.vars.get(name)
        if prev is not None:
            where = f"line {prev.loc.line}" if prev.loc else "a built-in declaration"
            raise _err(f"redefinition of '{name}'", node, f"'{name}' is already declared at {where}")
        if name in scope.structs:
            raise _err(f"redefinition of '{name}'", node, f"'{name}' is already a struct name")
        if scope.is_global and name in self.by_name:
            raise _err(f"'{name}' is already declared as a function", node,
                       f"rename the {what}")
        if name.startswith("gl_") and name not in BUILTIN_VARIABLES:
            raise _err(f"identifier '{name}' is reserved", node,
                       "names starting with 'gl_' belong to GLSL; choose another name")
        if Type.is_type_name(name) and name not in SOFT_TYPE_NAMES and is_keyword(
                name, self.info.version, "es" if self.info.es else self.info.profile):
            # (a type word that is not a keyword in this version, such as 'uint' in GLSL ES
            # 1.00, is an ordinary name there)
            raise _err(f"'{name}' is a type name and cannot be declared as a {what}", node)

    def _sizes_unsized_array(self, sym: Symbol) -> bool:
        """Whether ``sym`` redeclares an unsized array of this scope with an explicit size."""
        prev = self.scope.vars.get(sym.name)
        if prev is None or prev.kind != sym.kind or prev.loc is None:
            return False
        a, b = prev.type, sym.type
        return bool(a.dims and b.dims and a.dims[0] is None and b.dims[0] is not None
                    and a.dims[1:] == b.dims[1:] and a.base == b.base and a.size == b.size
                    and a.cols == b.cols and a.rows == b.rows
                    and a.struct_name == b.struct_name)

    def declare(self, sym: Symbol, node: Any) -> None:
        builtin = BUILTIN_VARIABLES.get(sym.name)
        prev = self.scope.vars.get(sym.name) if builtin is not None else None
        if builtin is not None and self.scope.is_global and (
                prev is None or (prev.kind == "builtin" and prev.type == sym.type and (
                    sym.name not in ("gl_FragCoord", "gl_FragDepth")
                    or _same_redeclaration(prev, sym)))):
            # Redeclaring a built-in (layout(origin_upper_left) in vec4 gl_FragCoord;); a
            # compatibility input may be redeclared again to add an interpolation qualifier
            # (in vec4 gl_Color; flat in vec4 gl_Color;); gl_FragCoord/gl_FragDepth again only
            # with the same qualifiers (4.60 §7.1.2: all their redeclarations must agree).
            sym.kind, sym.read_only = "builtin", builtin.read_only
        elif self._sizes_unsized_array(sym):
            # float u[][7]; ... float u[5][7];  -- an unsized array redeclared with its size:
            # the earlier symbol (and every use of it so far) takes the size.
            self.scope.vars[sym.name].type = sym.type
        else:
            self._check_new_name(sym.name, node, "variable")
        self.scope.vars[sym.name] = sym
        if self.scope.is_global:
            self.info.globals[sym.name] = sym
            bucket = {"uniform": self.info.uniforms, "in": self.info.inputs,
                      "out": self.info.outputs}.get(sym.kind)
            if bucket is not None:
                bucket[sym.name] = sym

    # ================================================================== types
    def type_of_spec(self, spec: A.TypeSpecifier) -> Type:
        if spec.struct is not None:
            t = self.struct_type(spec.struct)
        else:
            name = spec.name or ""
            if Type.is_type_name(name):
                t = Type.from_name(name)
            else:
                found = self.lookup(name)
                if not isinstance(found, Type):
                    raise _err(f"unknown type '{name}'", spec,
                               self._did_you_mean(name, types=True))
                t = found
        if spec.array_dims:
            t = t.array_of(*self.array_dims(spec.array_dims))
        return t

    def struct_type(self, st: A.StructSpecifier) -> Type:
        fields: list[tuple[str, Type]] = []
        seen: set[str] = set()
        for member in st.members:
            inner = member.type.spec.struct
            if inner is not None:
                raise _err(f"struct '{inner.name or '<anonymous>'}' is defined inside struct "
                           f"'{st.name or '<anonymous>'}'", member,
                           "GLSL has no embedded struct definitions; declare the inner struct "
                           "first and use its name")
            mtype = self.type_of_spec(member.type.spec)
            if mtype.is_void:
                raise _err("a struct member cannot be void", member)
            for d in member.declarators:
                if d.name in seen:
                    raise _err(f"duplicate member '{d.name}' in struct "
                               f"'{st.name or '<anonymous>'}'", d)
                seen.add(d.name)
                ft = mtype.array_of(*self.array_dims(d.array_dims)) if d.array_dims else mtype
                fields.append((d.name, ft))
        t = Type.struct(st.name or f"<anonymous@{st.loc.line if st.loc else 0}>", tuple(fields))
        if st.name:
            self._check_new_name(st.name, st, "struct")
            self.scope.structs[st.name] = t
            if self.scope.is_global:
                self.info.structs[st.name] = t
        return t

    def array_dims(self, dims: list) -> list[Optional[int]]:
        return [None if d is None else self.array_size(d) for d in dims]

    def array_size(self, expr: A.Expr) -> int:
        t = self.expr(expr)
        if not (t.is_integer and t.is_scalar):
            raise _err(f"array size must be an integer, not '{t}'", expr)
        value = self.const_value(expr)
        if value is None:
            raise _err("array size must be a constant integer expression", expr,
                       "use a literal or a 'const int' initialised with a constant")
        if value <= 0:
            raise _err(f"array size must be greater than zero, not {value}", expr)
        return int(value)

    # ================================================================== conversions
    def conv_rank(self, src: Type, dst: Type) -> Optional[int]:
        if src == dst:
            return 0
        if (src.size != dst.size or src.cols != dst.cols or src.rows != dst.rows
                or src.dims != dst.dims or src.base == "struct" or dst.base == "struct"):
            return None
        return self.conv.get((src.base, dst.base))

    def convertible(self, src: Type, dst: Type) -> bool:
        if src == dst:
            return True
        if src.dims and dst.dims and len(src.dims) == len(dst.dims) and dst.dims[0] is None:
            return self.convertible(src.element_type(), dst.element_type())
        return self.conv_rank(src, dst) is not None

    def common_base(self, a: Type, b: Type) -> Optional[str]:
        if a.base == b.base:
            return a.base
        if (a.base, b.base) in self.conv:
            return b.base
        if (b.base, a.base) in self.conv:
            return a.base
        return None

    # ================================================================== declarations
    def unit(self, unit: A.TranslationUnit) -> SemanticInfo:
        for decl in unit.decls:
            self.external(decl)
        self.finish(unit)
        return self.info

    def external(self, decl: A.Node) -> None:
        self.visit(decl)

    # a declaration, global or in a statement
    def visit_VariableDecl(self, decl: A.VariableDecl) -> None:
        self.var_decl(decl)

    def visit_PrecisionDecl(self, decl: A.PrecisionDecl) -> None:
        self.precision_decl(decl)

    def visit_FunctionDecl(self, decl: A.FunctionDecl) -> None:
        if not self.scope.is_global:
            raise _err("functions cannot be declared inside a function", decl)
        self.function(decl)

    def visit_InterfaceBlock(self, decl: A.InterfaceBlock) -> None:
        self.global_only(decl)
        self.interface_block(decl)

    def visit_QualifierDecl(self, decl: A.QualifierDecl) -> None:
        self.global_only(decl)
        self.qualifier_decl(decl)

    def global_only(self, decl: A.Node) -> None:
        if not self.scope.is_global:
            raise _err(f"{type(decl).__name__} is not allowed inside a function", decl)

    def generic_visit(self, node: A.Node) -> None:
        self.global_only(node)
        raise _err(f"unexpected declaration {type(node).__name__}", node)

    def layouts(self, qualifiers: list) -> None:
        for q in qualifiers:
            if isinstance(q, A.Layout):
                for _, value in q.items:
                    if value is not None:
                        self.expr(value)

    def precision_decl(self, decl: A.PrecisionDecl) -> None:
        t = self.type_of_spec(decl.spec)
        if not (t.base in ("float", "int") and t.is_scalar or t.is_opaque):
            raise _err(f"precision cannot be set for type '{t}'", decl,
                       "precision statements take float, int or a sampler type")

    def qualifier_decl(self, decl: A.QualifierDecl) -> None:
        self.layouts(decl.qualifiers)
        for name in decl.names:
            if self.lookup(name) is None and name not in BUILTIN_VARIABLES:
                raise _err(f"undeclared identifier '{name}'", decl)

    def storage_kind(self, quals: tuple[str, ...], node: Any) -> str:
        storage = [q for q in quals if q in _STORAGE]
        if self.scope.is_global:
            return _STORAGE[storage[0]] if storage else "global"
        for q in storage:
            if q != "const":
                raise _err(f"storage qualifier '{q}' is not allowed on a local variable", node,
                           "declare it at global scope")
        return "const" if storage else "local"

    def var_decl(self, decl: A.VariableDecl) -> None:
        self.layouts(decl.type.qualifiers)
        quals = _qual_words(decl.type)
        base = self.type_of_spec(decl.type.spec)
        if not decl.declarators:
            return
        kind = self.storage_kind(quals, decl)
        for d in decl.declarators:
            t = base.array_of(*self.array_dims(d.array_dims)) if d.array_dims else base
            if t.base == "void":
                raise _err(f"variable '{d.name}' cannot be declared void", d)
            if t.is_opaque and kind not in ("uniform", "global") and self.scope.is_global:
                raise _err(f"'{t}' variable '{d.name}' must be a uniform", d)
            if d.init is not None:
                if kind in ("in", "out"):
                    raise _err(f"{'input' if kind == 'in' else 'output'} variable '{d.name}' "
                               "cannot have an initializer", d.init)
                t = self.initializer(d.init, t, d.name)
            elif kind == "const":
                raise _err(f"const variable '{d.name}' must be initialized", d)
            read_only = kind in ("uniform", "in", "const") or "readonly" in quals
            sym = Symbol(d.name, t, kind, decl, d.loc or decl.loc, read_only, quals)
            if kind == "const" and d.init is not None:
                sym.const_value = self.const_value(d.init)
            self.declare(sym, d)

    def initializer(self, init: A.Expr, t: Type, name: str) -> Type:
        """Check ``init`` against the declared type ``t``; returns the completed type (an
        unsized array takes the initializer's size)."""
        if isinstance(init, A.InitList):
            return self.init_list(init, t)
        vt = self.expr(init)
        if t.dims and t.dims[0] is None and vt.dims and len(vt.dims) == len(t.dims):
            t = Type(t.base, t.size, t.cols, t.rows, (vt.dims[0],) + t.dims[1:], t.struct_name,
                     t.fields)
        if not self.convertible(vt, t):
            raise _err(f"cannot initialize '{name}' of type '{t}' with a value of type '{vt}'",
                       init, self._conversion_hint(vt, t))
        return t

    def init_list(self, node: A.InitList, t: Type) -> Type:
        items = node.items
        if t.dims:
            n = t.dims[0]
            if n is None:
                n = len(items)
                t = Type(t.base, t.size, t.cols, t.rows, (n,) + t.dims[1:], t.struct_name,
                         t.fields)
            if len(items) != n:
                raise _err(f"initializer list has {len(items)} elements for '{t}'", node)
            expected = [t.element_type()] * n
        elif t.is_struct:
            if len(items) != len(t.fields):
                raise _err(f"initializer list has {len(items)} elements for struct '{t}' "
                           f"with {len(t.fields)} members", node)
            expected = [ft for _, ft in t.fields]
        elif t.is_matrix:
            if len(items) != t.cols:
                raise _err(f"initializer list for '{t}' needs {t.cols} columns", node)
            expected = [t.column_type()] * t.cols
        elif t.is_vector:
            if len(items) != t.size:
                raise _err(f"initializer list for '{t}' needs {t.size} components", node)
            expected = [t.scalar_type()] * t.size
        else:
            raise _err(f"an initializer list cannot initialize a '{t}'", node)
        for item, et in zip(items, expected):
            self.initializer(item, et, "element")
        node.type = t
        return t

    def interface_block(self, block: A.InterfaceBlock) -> None:
        self.layouts(block.qualifiers)
        quals = tuple(q for q in block.qualifiers if isinstance(q, str))
        kind = self.storage_kind(quals, block)
        fields: list[tuple[str, Type]] = []
        for member in block.members:
            mtype = self.type_of_spec(member.type.spec)
            if mtype.contains_opaque() and not self.bindless:
                raise _err(f"block member of type '{mtype}' is not allowed", member,
                           "samplers, images and atomic counters are declared as uniforms "
                           "outside blocks")
            for d in member.declarators:
                ft = mtype.array_of(*self.array_dims(d.array_dims)) if d.array_dims else mtype
                fields.append((d.name, ft))
        read_only = kind in ("uniform", "in") or "readonly" in quals
        if block.instance_name:
            t = Type.struct(block.block_name, tuple(fields))
            if block.array_dims:
                t = t.array_of(*self.array_dims(block.array_dims))
            self.declare(Symbol(block.instance_name, t, kind, block, block.loc, read_only, quals),
                         block)
        else:
            for (name, ft), loc in zip(fields, [d.loc for m in block.members
                                                 for d in m.declarators]):
                self.declare(Symbol(name, ft, kind, block, loc or block.loc, read_only, quals),
                             block)

    # ================================================================== functions
    def function(self, fd: A.FunctionDecl) -> None:
        ret = self.type_of_spec(fd.return_type.spec)
        ptypes, pquals = [], []
        for p in fd.params:
            pt = self.type_of_spec(p.type.spec)
            if p.array_dims:
                pt = pt.array_of(*self.array_dims(p.array_dims))
            if pt.is_void:
                raise _err("a parameter cannot be void", p)
            words = _qual_words(p.type)
            pquals.append("inout" if "inout" in words else "out" if "out" in words else "in")
            ptypes.append(pt)
        key = (fd.name, tuple(ptypes))
        uf = next((f for f in self.by_name.get(fd.name, []) if f.param_types == key[1]), None)
        if uf is None:
            if fd.name in self.global_scope.vars or fd.name in self.global_scope.structs:
                raise _err(f"'{fd.name}' is already declared as a variable or type", fd)
            if Type.is_type_name(fd.name) and fd.name not in SOFT_TYPE_NAMES:
                raise _err(f"'{fd.name}' is a type name and cannot name a function", fd)
            uf = UserFunction(fd.name, ret, tuple(ptypes), tuple(pquals))
            self.by_name.setdefault(fd.name, []).append(uf)
            self.info.functions[uf.signature()] = uf
            self.info.call_graph.setdefault(uf.signature(), set())
        else:
            if uf.return_type != ret:
                raise _err(f"function '{uf.signature()}' redeclared with return type '{ret}'", fd,
                           f"it was declared returning '{uf.return_type}' at line "
                           f"{uf.decl.loc.line if uf.decl.loc else '?'}")
            if uf.param_quals != tuple(pquals):
                raise _err(f"function '{uf.signature()}' redeclared with different parameter "
                           "qualifiers", fd)
            if fd.body is not None and uf.definition is not None:
                first = uf.definition.loc.line if uf.definition.loc else "?"
                raise _err(f"redefinition of function '{uf.signature()}'", fd,
                           f"it is already defined at line {first}")
        if fd.name == "main":
            if ptypes or not ret.is_void:
                raise _err("'main' must be declared 'void main()'", fd)
        if fd.body is None:
            if uf.prototype is None:
                uf.prototype = fd
            return
        uf.definition = fd
        if fd.name == "main":
            self.info.main = fd
        self.current = uf
        self.push()
        for p, pt, q in zip(fd.params, ptypes, pquals):
            if p.name:
                words = _qual_words(p.type)
                self.declare(Symbol(p.name, pt, "param", p, p.loc, "const" in words,
                                    words or (q,)), p)
        for stmt in fd.body.stmts:
            self.stmt(stmt)
        self.pop()
        self.current = None

    def finish(self, unit: A.TranslationUnit) -> None:
        if self.info.main is None:
            raise SemanticError("the shader has no 'main' function",
                                unit.loc or SourceLoc("<string>", 1, 1),
                                "a fragment shader needs 'void main() { ... }'")
        for call, uf in self.calls:
            if uf.definition is None:
                raise _err(f"function '{uf.signature()}' is declared but never defined", call,
                           "add a body for it, or remove the call")
            call.target = uf.definition
        self._check_recursion()

    def _check_recursion(self) -> None:
        graph = self.info.call_graph
        state: dict[str, int] = {}
        stack: list[str] = []

        def visit(node: str) -> None:
            state[node] = 1
            stack.append(node)
            for callee in sorted(graph.get(node, ()), key=position):
                if state.get(callee) == 1:
                    cycle = stack[stack.index(callee):] + [callee]
                    names = " -> ".join(s.split("(")[0] for s in cycle)
                    loc = self.edge_loc.get((node, callee))
                    raise SemanticError(f"recursion is not allowed: {names}", loc,
                                        "GLSL forbids recursive calls; rewrite it as a loop")
                if callee not in state:
                    visit(callee)
            stack.pop()
            state[node] = 2

        def position(sig: str) -> tuple[int, int]:
            loc = self.info.functions[sig].decl.loc
            return (loc.line, loc.col) if loc else (0, 0)

        for sig in sorted(graph, key=position):  # report cycles from the first definition
            if sig not in state:
                visit(sig)

    # ================================================================== statements
    def stmt(self, s: A.Stmt) -> None:
        self.visit(s)

    def sub_stmt(self, s: A.Stmt) -> None:
        if isinstance(s, A.Compound):
            self.visit_Compound(s)
        else:
            self.push()
            self.stmt(s)
            self.pop()

    def visit_Compound(self, s: A.Compound) -> None:
        self.push()
        for sub in s.stmts:
            self.stmt(sub)
        self.pop()

    def visit_DeclStmt(self, s: A.DeclStmt) -> None:
        self.visit(s.decl)

    def visit_Discard(self, s: A.Discard) -> None:
        pass

    def visit_ExprStmt(self, s: A.ExprStmt) -> None:
        if s.expr is not None:
            self.expr(s.expr)

    def condition(self, cond: Union[A.Expr, A.VariableDecl], what: str) -> None:
        if isinstance(cond, A.VariableDecl):
            self.var_decl(cond)
            t = self.scope.vars[cond.declarators[0].name].type
            node: Any = cond
        else:
            t = self.expr(cond)
            node = cond
        if t != BOOL:
            raise _err(f"{what} condition must be a scalar bool, not '{t}'", node)

    def visit_If(self, s: A.If) -> None:
        self.condition(s.cond, "if")
        self.sub_stmt(s.then)
        if s.else_ is not None:
            self.sub_stmt(s.else_)

    def _loop_body(self, body: A.Stmt) -> None:
        self.loops += 1
        self.sub_stmt(body)
        self.loops -= 1

    def visit_For(self, s: A.For) -> None:
        self.push()
        if s.init is not None:
            self.stmt(s.init)
        if s.cond is not None:
            self.condition(s.cond, "for-loop")
        if s.step is not None:
            self.expr(s.step)
        self._loop_body(s.body)
        self.pop()

    def visit_While(self, s: A.While) -> None:
        self.push()
        self.condition(s.cond, "while-loop")
        self._loop_body(s.body)
        self.pop()

    def visit_DoWhile(self, s: A.DoWhile) -> None:
        self._loop_body(s.body)
        self.condition(s.cond, "do-while")

    def visit_Switch(self, s: A.Switch) -> None:
        t = self.expr(s.expr)
        if not (t.is_integer and t.is_scalar):
            raise _err(f"switch expression must be a scalar integer, not '{t}'", s.expr)
        self.switches.append(set())
        self.visit_Compound(s.body)
        self.switches.pop()

    def visit_Case(self, s: A.Case) -> None:
        if not self.switches:
            raise _err("'case' label outside a switch", s)
        labels = self.switches[-1]
        if s.expr is None:
            key: Any = "default"
        else:
            t = self.expr(s.expr)
            if not (t.is_integer and t.is_scalar):
                raise _err(f"case label must be a scalar integer, not '{t}'", s.expr)
            key = self.const_value(s.expr)
            if key is None:
                raise _err("case label must be a constant expression", s.expr)
        if key in labels:
            raise _err(f"duplicate case label '{key}'", s)
        labels.add(key)

    def visit_Break(self, s: A.Break) -> None:
        if not self.loops and not self.switches:
            raise _err("'break' outside a loop or switch", s)

    def visit_Continue(self, s: A.Continue) -> None:
        if not self.loops:
            raise _err("'continue' outside a loop", s)

    def visit_Return(self, s: A.Return) -> None:
        assert self.current is not None
        ret = self.current.return_type
        if s.expr is None:
            if not ret.is_void:
                raise _err(f"function '{self.current.name}' must return a value of type "
                           f"'{ret}'", s)
            return
        t = self.expr(s.expr)
        if ret.is_void:
            raise _err(f"void function '{self.current.name}' cannot return a value", s.expr)
        if not self.convertible(t, ret):
            raise _err(f"cannot return a value of type '{t}' from function "
                       f"'{self.current.name}' returning '{ret}'", s.expr,
                       self._conversion_hint(t, ret))

    # ================================================================== expressions
    def expr(self, e: A.Expr) -> Type:
        t = self.visit(e)
        e.type = t
        return t

    def visit_IntLit(self, e: A.IntLit) -> Type:
        if e.text and e.text[-1] in "lL":  # 64-bit literal: 1l, 2ul
            return UINT64 if e.unsigned else INT64
        return UINT if e.unsigned else INT

    def visit_FloatLit(self, e: A.FloatLit) -> Type:
        if e.text and e.text[-2:] in ("hf", "HF"):  # half-float literal
            return FLOAT16
        return DOUBLE if e.double else FLOAT

    def visit_BoolLit(self, e: A.BoolLit) -> Type:
        return BOOL

    def visit_Ident(self, e: A.Ident) -> Type:
        found = self.lookup(e.name)
        if isinstance(found, Symbol):
            sym = found
        elif found is not None:
            raise _err(f"'{e.name}' is a type, not a variable", e)
        else:
            sym = self.builtin_symbols.get(e.name)
            if sym is None:
                var = BUILTIN_VARIABLES.get(e.name)
                if var is None:
                    if e.name in self.by_name or builtin_lookup(e.name):
                        raise _err(f"'{e.name}' is a function, not a variable", e,
                                   f"call it: {e.name}(...)")
                    raise _err(f"undeclared identifier '{e.name}'", e, self._did_you_mean(e.name))
                sym = Symbol(var.name, var.type, "builtin", var, None, var.read_only,
                             (var.kind,), var.value)
                self.builtin_symbols[e.name] = sym
        e.symbol = sym
        if self.current is not None and sym.kind not in ("local", "param") and (
                sym.kind == "builtin" or self.global_scope.vars.get(sym.name) is sym):
            self.info.used_globals.add(sym.name)
        return sym.type

    def visit_Sequence(self, e: A.Sequence) -> Type:
        t = VOID
        for sub in e.exprs:
            t = self.expr(sub)
        return t

    def visit_InitList(self, e: A.InitList) -> Type:
        raise _err("an initializer list '{...}' can only initialize a variable", e,
                   "use a constructor such as vec3(...) or float[3](...)")

    # ---------------------------------------------------------------- operators
    def visit_Unary(self, e: A.Unary) -> Type:
        t = self.expr(e.operand)
        op = e.op
        if op in ("+", "-"):
            if not t.is_numeric:
                raise _err(f"unary '{op}' cannot be applied to '{t}'", e)
        elif op == "!":
            if t != BOOL:
                raise _err(f"'!' needs a scalar bool, not '{t}'", e, "use not() for bvec")
        elif op == "~":
            if not t.is_integer:
                raise _err(f"'~' needs an integer operand, not '{t}'", e)
        else:  # ++ / --
            if not t.is_numeric:
                raise _err(f"'{op}' cannot be applied to '{t}'", e)
            self.check_lvalue(e.operand, op)
        return t

    def visit_Binary(self, e: A.Binary) -> Type:
        lt = self.expr(e.left)
        rt = self.expr(e.right)
        return self.binary_type(e.op, lt, rt, e)

    def binary_type(self, op: str, lt: Type, rt: Type, node: Any) -> Type:
        if op in ("&&", "||", "^^"):
            if lt != BOOL or rt != BOOL:
                raise _err(f"'{op}' needs scalar bool operands, not '{lt}' and '{rt}'", node)
            return BOOL
        if op in ("==", "!="):
            if lt.contains_opaque() or rt.contains_opaque() or lt.is_void or rt.is_void:
                raise _err(f"'{op}' cannot compare '{lt}' and '{rt}'", node)
            if lt != rt and not (self.conv_rank(lt, rt) is not None
                                 or self.conv_rank(rt, lt) is not None):
                raise _err(f"'{op}' cannot compare '{lt}' and '{rt}'", node,
                           "both sides must have the same type")
            return BOOL
        if op in ("<", ">", "<=", ">="):
            if not (lt.is_numeric and rt.is_numeric and lt.is_scalar and rt.is_scalar
                    and self.common_base(lt, rt)):
                raise _err(f"'{op}' needs scalar numeric operands, not '{lt}' and '{rt}'", node,
                           "use lessThan()/greaterThan() for vectors")
            return BOOL
        if op in ("<<", ">>"):
            if not (lt.is_integer and rt.is_integer and not lt.is_matrix):
                raise _err(f"'{op}' needs integer operands, not '{lt}' and '{rt}'", node)
            if not (rt.is_scalar or rt.size == lt.size):
                raise _err(f"'{op}' cannot shift '{lt}' by '{rt}'", node)
            return lt
        # arithmetic and bitwise
        if not (lt.is_numeric and rt.is_numeric):
            raise _err(f"'{op}' cannot be applied to '{lt}' and '{rt}'", node)
        base = self.common_base(lt, rt)
        if base is None:
            raise _err(f"'{op}' cannot be applied to '{lt}' and '{rt}'", node,
                       self._conversion_hint(lt, rt))
        if op in ("%", "&", "|", "^") and base not in INTEGER_BASES:
            raise _err(f"'{op}' needs integer operands, not '{lt}' and '{rt}'", node)
        l = lt.with_base(base) if lt.base != base else lt
        r = rt.with_base(base) if rt.base != base else rt
        if op == "*" and (l.is_matrix or r.is_matrix) and not (l.is_scalar or r.is_scalar):
            if l.is_matrix and r.is_matrix:
                if l.cols != r.rows:
                    raise _err(f"cannot multiply '{lt}' by '{rt}'", node,
                               "the left matrix needs as many columns as the right one has rows")
                return Type.matrix(r.cols, l.rows, base)
            if l.is_matrix:
                if l.cols != r.size:
                    raise _err(f"cannot multiply '{lt}' by '{rt}'", node)
                return Type(base, l.rows)
            if l.size != r.rows:
                raise _err(f"cannot multiply '{lt}' by '{rt}'", node)
            return Type(base, r.cols)
        if l == r:
            return l
        if l.is_scalar:
            return r
        if r.is_scalar:
            return l
        raise _err(f"'{op}' cannot be applied to '{lt}' and '{rt}'", node,
                   "the operands need the same size, or one of them must be a scalar")

    def visit_Assign(self, e: A.Assign) -> Type:
        tt = self.expr(e.target)
        vt = self.expr(e.value)
        self.check_lvalue(e.target, e.op)
        if e.op == "=":
            if tt.contains_opaque() and not self.bindless:
                raise _err(f"cannot assign to a variable of type '{tt}'", e.target)
            if not self.convertible(vt, tt):
                raise _err(f"cannot assign a value of type '{vt}' to '{tt}'", e,
                           self._conversion_hint(vt, tt))
            return tt
        result = self.binary_type(_ASSIGN_TO_BINARY[e.op], tt, vt, e)
        if result != tt:
            raise _err(f"'{e.op}' gives a '{result}', which cannot be stored in '{tt}'", e)
        return tt

    def check_lvalue(self, target: A.Expr, op: str) -> None:
        node = target
        while True:
            if isinstance(node, A.Ident):
                sym = node.symbol
                if sym.read_only:
                    word = _KIND_WORDS.get(sym.kind, "read-only variable")
                    raise _err(f"cannot assign to {word} '{sym.name}'", target,
                               self._readonly_hint(sym))
                return
            if isinstance(node, A.Field):
                obj_t = node.obj.type
                if (obj_t.is_scalar or obj_t.is_vector) and len(set(node.name)) != len(node.name):
                    raise _err(f"cannot assign to swizzle '.{node.name}' with repeated "
                               "components", node)
                node = node.obj
            elif isinstance(node, A.Index):
                node = node.obj
            else:
                what = "'" + op + "'" if op in ("++", "--") else "assignment"
                raise _err(f"the target of {what} is not an l-value", target,
                           "only variables, their fields, swizzles and elements can be assigned")

    def visit_Ternary(self, e: A.Ternary) -> Type:
        ct = self.expr(e.cond)
        if ct != BOOL:
            raise _err(f"'?:' condition must be a scalar bool, not '{ct}'", e.cond)
        a = self.expr(e.then)
        b = self.expr(e.else_)
        if a == b:
            return a
        if self.conv_rank(a, b) is not None:
            return b
        if self.conv_rank(b, a) is not None:
            return a
        raise _err(f"the branches of '?:' have different types: '{a}' and '{b}'", e)

    # ---------------------------------------------------------------- postfix
    def visit_Field(self, e: A.Field) -> Type:
        t = self.expr(e.obj)
        if t.base == "struct" and not t.dims:
            ft = t.field_type(e.name)
            if ft is None:
                raise _err(f"'{t}' has no member named '{e.name}'", e,
                           self._close(e.name, [n for n, _ in t.fields]))
            return ft
        if t.is_scalar or t.is_vector:
            return swizzle(t, e.name, e.loc)[0]
        raise _err(f"'{t}' has no member named '{e.name}'", e)

    def visit_Index(self, e: A.Index) -> Type:
        t = self.expr(e.obj)
        it = self.expr(e.index)
        if not (it.is_integer and it.is_scalar):
            raise _err(f"index must be a scalar integer, not '{it}'", e.index)
        if t.dims:
            result, bound = t.element_type(), t.dims[0]
        elif t.is_matrix:
            result, bound = t.column_type(), t.cols
        elif t.is_vector:
            result, bound = t.scalar_type(), t.size
        else:
            raise _err(f"cannot index a value of type '{t}'", e)
        value = self.const_value(e.index)
        if value is not None and (value < 0 or (bound is not None and value >= bound)):
            raise _err(f"index {value} is out of range for '{t}'", e.index,
                       f"valid indices are 0 to {bound - 1}" if bound else None)
        return result

    def visit_Length(self, e: A.Length) -> Type:
        t = self.expr(e.obj)
        if not (t.dims or t.is_vector or t.is_matrix):
            raise _err(f"length() cannot be applied to '{t}'", e,
                       "it works on arrays, vectors and matrices")
        return INT

    # ---------------------------------------------------------------- calls
    def visit_Call(self, e: A.Call) -> Type:
        args = [self.expr(a) for a in e.args]
        if e.array_dims is not None:
            elem = self._named_type(e.name, e)
            dims = [None if d is None else self.array_size(d) for d in e.array_dims]
            return self.construct(elem.array_of(*dims), args, e)
        if Type.is_type_name(e.name) and e.name not in SOFT_TYPE_NAMES:
            return self.construct(Type.from_name(e.name), args, e)
        found = self.lookup(e.name)
        if isinstance(found, Type):
            return self.construct(found, args, e)
        if isinstance(found, Symbol) and not self.scope.is_global and \
                self.global_scope.vars.get(e.name) is not found:
            raise _err(f"'{e.name}' is a variable, not a function", e)
        return self.function_call(e, args)

    def _named_type(self, name: str, node: Any) -> Type:
        if Type.is_type_name(name):
            return Type.from_name(name)
        found = self.lookup(name)
        if isinstance(found, Type):
            return found
        raise _err(f"unknown type '{name}'", node, self._did_you_mean(name, types=True))

    def function_call(self, e: A.Call, args: list[Type]) -> Type:
        user = self.by_name.get(e.name, [])
        builtins = builtin_lookup(e.name)
        if not user and not builtins:
            raise _err(f"undeclared function '{e.name}'", e, self._did_you_mean(e.name, True))
        key = (e.name, tuple(args), len(user))
        if key in self.overload_cache:
            target = self.overload_cache[key]
        else:
            target = self.resolve(e, user, builtins, args)
            self.overload_cache[key] = target
        for i, (q, arg) in enumerate(zip(target.qualifiers, e.args)):
            if q != "in":
                try:
                    self.check_lvalue(arg, "=")
                except SemanticError as err:
                    raise _err(f"argument {i + 1} of '{e.name}' is an '{q}' parameter and must "
                               f"be a writable variable", arg, err.message) from None
        e.target = target
        if isinstance(target, BuiltinFunction):
            e.kind = "builtin"
            self.info.builtins_used.add(e.name)
        else:
            e.kind = "function"
            self.calls.append((e, target))
            if self.current is not None:
                edge = (self.current.signature(), target.signature())
                self.info.call_graph[edge[0]].add(edge[1])
                self.edge_loc.setdefault(edge, e.loc)
        return target.return_type

    def resolve(self, e: A.Call, user: list, builtins: list, args: list[Type]) -> Any:
        scored: list[tuple[Any, list[int]]] = []
        for cand in user + builtins:
            params = cand.params
            if len(params) != len(args):
                continue
            ranks = []
            for p, a, q in zip(params, args, cand.qualifiers):
                r = (self.conv_rank(a, p) if q == "in" else
                     self.conv_rank(p, a) if q == "out" else (0 if a == p else None))
                if r is None:
                    break
                ranks.append(r)
            else:
                scored.append((cand, ranks))
        if not scored:
            everything = user + builtins  # same-arity candidates first: the likeliest intent
            shown = sorted(everything, key=lambda c: (
                len(c.params) != len(args), not (c.params and c.params[0] == args[0])))
            listed = "; ".join(str(c) for c in shown[:8])
            more = f" (and {len(shown) - 8} more)" if len(shown) > 8 else ""
            raise _err(f"no matching overload for '{e.name}({', '.join(map(str, args))})'", e,
                       f"candidates: {listed}{more}")
        exact = [c for c, r in scored if not any(r)]
        if exact:
            return exact[0]  # user functions come first and hide a built-in of that signature
        best = [c for c, r in scored
                if all(all(x <= y for x, y in zip(r, r2)) for _, r2 in scored)]
        if len(best) != 1:
            raise _err(f"ambiguous call to '{e.name}({', '.join(map(str, args))})'", e,
                       "candidates: " + "; ".join(str(c) for c, _ in scored[:6])
                       + "; add an explicit conversion")
        return best[0]

    def construct(self, t: Type, args: list[Type], e: A.Call) -> Type:
        e.kind = "constructor"
        if not args:
            raise _err(f"constructor of '{t}' needs arguments", e)
        combined = _combined_sampler(t, args) or _bindless_handle(t, args)
        if combined is not None:
            e.target = combined
            return combined
        if t.dims:
            elem = t.element_type()
            n = t.dims[0]
            if n is None:
                t = Type(t.base, t.size, t.cols, t.rows, (len(args),) + t.dims[1:],
                         t.struct_name, t.fields)
            elif n != len(args):
                raise _err(f"array constructor of '{t}' has {len(args)} arguments", e)
            for i, a in enumerate(args):
                if not self.convertible(a, elem):
                    raise _err(f"argument {i + 1} of the '{t}' constructor has type '{a}', "
                               f"not '{elem}'", e.args[i])
            e.target = t
            return t
        e.target = t
        if t.base == "struct":
            if len(args) != len(t.fields):
                raise _err(f"constructor of struct '{t}' needs {len(t.fields)} arguments, "
                           f"got {len(args)}", e,
                           "members: " + ", ".join(f"{ft} {n}" for n, ft in t.fields))
            for i, (a, (fname, ft)) in enumerate(zip(args, t.fields)):
                if not self.convertible(a, ft):
                    raise _err(f"argument {i + 1} of the '{t}' constructor has type '{a}', but "
                               f"member '{fname}' is '{ft}'", e.args[i])
            return t
        if not t.is_basic:
            m = None if t.base in SOFT_TYPE_NAMES else _SAMPLER_RE.match(t.base)
            raise _err(f"cannot construct a value of type '{t}'", e,
                       f"a combined sampler is built as {t.base}({m.group(1)}texture"
                       f"{m.group(2)}, sampler{m.group(3) or ''})" if m else None)
        for i, a in enumerate(args):
            if not a.is_basic:
                raise _err(f"argument {i + 1} of the '{t}' constructor has type '{a}'", e.args[i],
                           "constructors take scalars, vectors and matrices")
        if len(args) == 1:
            a = args[0]
            if a.is_scalar or t.is_scalar or (t.is_matrix and a.is_matrix):
                return t
            if a.components < t.components:
                raise _err(f"not enough data to construct '{t}' from '{a}'", e)
            return t
        if t.is_matrix and any(a.is_matrix for a in args):
            raise _err(f"a matrix argument to the '{t}' constructor must be its only argument",
                       e)
        total = 0
        for i, a in enumerate(args):
            if total >= t.components:
                raise _err(f"too many arguments to the '{t}' constructor", e.args[i],
                           f"'{t}' has {t.components} components")
            total += a.components
        if total < t.components:
            raise _err(f"not enough data to construct '{t}': {total} of {t.components} "
                       "components", e)
        return t

    # ================================================================== constant folding
    def const_value(self, e: A.Expr) -> Any:
        """The value of a constant expression (scalars, vectors, matrices, arrays, structs; see
        :mod:`rrcache.glsl.constfold`), or None when it is not one."""
        return const_value(e)

    # ================================================================== hints
    def _visible_names(self, types: bool = False, functions: bool = False) -> list[str]:
        names: list[str] = []
        s: Optional[_Scope] = self.scope
        while s is not None:
            names += list(s.structs) if types else list(s.vars)
            s = s.parent
        if functions:
            from rrcache.glsl.builtins import BUILTIN_FUNCTIONS
            names += list(self.by_name) + list(BUILTIN_FUNCTIONS)
        elif not types:
            names += list(BUILTIN_VARIABLES)
        return names

    def _did_you_mean(self, name: str, functions: bool = False, types: bool = False
                      ) -> Optional[str]:
        return self._close(name, self._visible_names(types, functions))

    @staticmethod
    def _close(name: str, names: list[str]) -> Optional[str]:
        match = difflib.get_close_matches(name, names, n=1, cutoff=0.75)
        return f"did you mean '{match[0]}'?" if match else None

    def _conversion_hint(self, src: Type, dst: Type) -> Optional[str]:
        if src.size == dst.size and src.cols == dst.cols and src.base != dst.base and \
                src.is_basic and dst.is_basic:
            if not self.conv:
                return (f"this GLSL version has no implicit conversions; write "
                        f"{dst.short_name()}(...) or use a literal of the right type "
                        "(1.0, not 1)")
            return f"convert it explicitly: {dst.short_name()}(...)"
        return None

    def _readonly_hint(self, sym: Symbol) -> Optional[str]:
        if sym.kind == "uniform":
            return "uniforms are set by the application; copy it into a local variable first"
        if sym.kind == "in":
            return "shader inputs are read-only; copy it into a local variable first"
        if sym.kind == "const":
            return "remove 'const' from its declaration to modify it"
        return None


_SAMPLER_RE = re.compile(r"^([iu]?)sampler(\d\w*?|Cube\w*?|Buffer)(Shadow)?$")


def _combined_sampler(t: Type, args: list[Type]) -> Optional[Type]:
    """The type built by a Vulkan combined-sampler constructor, or None when ``t(args)`` is not
    one: ``sampler2D(texture2D, sampler)``, ``sampler2DShadow(texture2D, samplerShadow)`` and
    the array form ``sampler3D[4](texture3D[4], sampler)``."""
    m = _SAMPLER_RE.match(t.base)
    if not m or len(args) != 2 or args[1].dims or args[1].base not in ("sampler", "samplerShadow"):
        return None
    tex = args[0]
    if tex.base != f"{m.group(1)}texture{m.group(2)}" or len(tex.dims) != len(t.dims):
        return None
    if t.dims and t.dims[0] is not None and t.dims != tex.dims:
        return None
    return t.without_array().array_of(*tex.dims) if t.dims else t


def _bindless_handle(t: Type, args: list[Type]) -> Optional[Type]:
    """GL_ARB_bindless_texture: a sampler or image made from its 64-bit handle, ``sampler2D(uvec2)``,
    and the handle of one, ``uvec2(sampler2D)``; None for any other constructor."""
    if len(args) != 1 or t.dims or args[0].dims:
        return None
    handle = Type("uint", 2)
    if t.is_opaque and t.base != "atomic_uint" and t.base not in SOFT_TYPE_NAMES \
            and args[0] == handle:
        return t
    a = args[0]
    if t == handle and a.is_opaque and a.base != "atomic_uint" and a.base not in SOFT_TYPE_NAMES:
        return t
    return None


def check(unit: A.TranslationUnit, filename: Optional[str] = None) -> SemanticInfo:
    """Type-check a parsed fragment shader in place and describe it.

    Sets ``Expr.type`` on every expression, ``Ident.symbol``, ``Call.kind`` and ``Call.target``;
    raises :class:`SemanticError` (one, at the first problem) on an invalid shader. ``filename``
    is accepted for symmetry with the other stages; locations come from the AST.

    >>> from rrcache.glsl.parser import parse_source
    >>> unit = parse_source("void main() { vec3 n = normalize(vec3(1.0)); gl_FragColor = vec4(n, 1.0); }")
    >>> info = check(unit)
    >>> sorted(info.builtins_used), sorted(info.used_globals)
    (['normalize'], ['gl_FragColor'])
    """
    return _Checker(unit).unit(unit)

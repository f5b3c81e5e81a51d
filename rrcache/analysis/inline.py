"""Pass: inline every user-function call site.

After this pass each call's subexpressions are distinct AST nodes (the paper's per-octave nodes
inside ``noise()`` exist only this way). The result is a valid GLSL program equivalent to the
input, built as follows.

- Function bodies are processed callee-first, so a body that is inlined no longer contains
  inlinable calls itself.
- A call ``f(a, b)`` inside a statement becomes, *before* that statement::

      float _rr_f_7;                       // the result (non-void functions)
      {
          vec3 _rr_p_8 = a;                // ``in``/``inout`` parameters copy their argument
          float _rr_q_9;                   // ``out`` parameters start undefined
          ...body, every local renamed _rr_<name>_<n>, ``return e`` -> ``_rr_f_7 = e``...
          b = _rr_q_9;                     // ``out``/``inout`` write-backs, in parameter order
      }

  and the call itself becomes ``_rr_f_7``. A sampler, image or atomic-counter argument (or a
  struct holding one) is not copied (GLSL has no local variables of those types): the argument
  itself stands for the parameter in the body (``texture(u_tex, uv)``). Calls are hoisted in
  evaluation order (arguments
  first, left to right). When a hoisted call has side effects (it writes a global or an
  ``out`` parameter, or calls a side-effecting built-in) or an operand evaluated before it has
  side effects (an assignment, ``++``), those earlier operands are hoisted into temporaries too,
  so the order of effects is kept. Index expressions of ``out`` arguments are evaluated once.
- Conditionally evaluated operands stay conditional: a call on the right of ``&&``/``||`` or in
  a branch of ``?:`` turns that operator into an ``if``.
- Calls in a ``while``/``for`` condition move into the loop (``for (;;) { ...; if (!c) break;
  ... }``); in a ``for`` step or ``do``-``while`` condition they move to the end of the body
  unless the body has a ``continue``, in which case that call is not inlined.
- Early returns: ``return`` inside ``if``/``else`` nests becomes an assignment to the result plus
  ``_rr_live_<n> = false``, and the statements after it run under ``if (_rr_live_<n>)`` (the
  cacheable-node analysis treats such guards like code after a ``return``: not dynamic).
  A function with a ``return`` inside a loop or ``switch`` is *not inlined*: it stays a function,
  and the cacheable-node analysis marks the nodes in its body ``dynamic``.
- A call of a function without effects whose arguments print the same as those of an earlier
  call in the same statement (``map(p).x + map(p).y``) reads that call's result: one inlined
  body, not two.
- Bounded: before anything is inlined, the syntax nodes all call sites would copy (each call
  copies its callee's body, the callee's own calls inlined) are counted against
  ``budget.analysis_nodes`` (``rrcache --max-ast-nodes``); beyond it the shader is refused with
  a :class:`~rrcache.errors.GLSLError` naming the deepest chain of calls (a chain of 2,000
  functions each calling the previous would copy 12 million). A function's body is moved, not
  copied, into its last call site.
- Functions no longer called are removed. Names starting with ``_rr`` are reserved. A function
  kept (a ``return`` inside a loop) gets a prototype before its first use when a call to it
  now stands above its definition (an inlined body defined later called it).
- A body inlined into another function keeps meaning what it meant: a local or parameter of
  the caller named like a global or a function the body uses (``float pos`` where the body
  reads the global ``vec3 pos``; ``float step`` where it calls ``step()``) is renamed first,
  and a definition that now uses a global or struct type declared after it (``main`` written
  before the helpers and their globals) moves after that declaration, its prototype left in
  place.
- A ``?:`` of ``void`` calls used as a statement becomes an ``if``.

>>> from rrcache.glsl.frontend import parse_shader
>>> s = parse_shader("float sq(float x) { return x * x; }\\n"
...                  "void main() { gl_FragColor = vec4(sq(gl_FragCoord.x)); }")
>>> out = inline_calls(s)
>>> [d.name for d in out.unit.decls]
['main']
"""
from __future__ import annotations

import dataclasses
from typing import Optional

from rrcache.budgets import budget
from rrcache.errors import GLSLError, UnsupportedShaderError
from rrcache.glsl import ast as A
from rrcache.glsl.printer import print_expr
from rrcache.glsl.semantic import check

from rrcache.glsl.ast import children, is_literal, walk
from rrcache.glsl.rewrite import (
    NameAllocator, assign, check_reserved_names, clone, declare, declare_typed, rewrite_scoped,
    with_chain,
)
from rrcache.glsl.defuse import definitions, out_qualifiers, param_qualifier
from rrcache.glsl.visitor import NodeVisitor

__all__ = ["inline_calls", "inline_unit"]

_RET = "$ret"      # placeholders in a prepared body; renamed at each call site
_LIVE = "$live"


def inline_calls(shader):
    """Return a copy of ``shader`` with every user-function call site inlined (see the module
    docstring for how). The input is not modified; the result is type-checked again.

    >>> from rrcache.glsl.frontend import parse_shader
    >>> s = parse_shader("float f(float x) { return x + 1.0; }\\n"
    ...                  "void main() { gl_FragColor = vec4(f(gl_FragCoord.x)); }")
    >>> from rrcache.glsl.printer import print_glsl
    >>> "f(" in print_glsl(inline_calls(s).unit)
    False
    """
    unit = inline_unit(shader.unit)
    info = check(unit, shader.path or "<string>")
    return dataclasses.replace(shader, unit=unit, info=info)


def inline_unit(unit: A.TranslationUnit) -> A.TranslationUnit:
    """The inlining pass on a checked translation unit; returns a new, *unchecked* unit."""
    check_reserved_names(unit)
    return _Inliner(unit).run()


class _Template:
    """A function body (callee-first: its own calls already inlined) ready to be inlined; each
    instance has its returns converted to placeholder assignments."""

    def __init__(self, decl: A.FunctionDecl, needs_flag: bool, uses: int):
        self.decl = decl
        self.needs_flag = needs_flag
        self.is_void = decl.return_type.spec.name == "void"
        # call sites still to inline it: the last one takes the body itself instead of a copy
        # (each node would otherwise be copied once per level of nesting, and every function
        # of a chain would keep its whole inlined body)
        self.uses = uses

    def release(self) -> None:
        """One call site less (a shared one): on the last, the body is no longer kept."""
        self.uses -= 1
        if self.uses <= 0:
            self.decl.body = A.Compound([], loc=self.decl.body.loc)

    def instantiate(self, site: str) -> A.Compound:
        """The body for one call site, every location tagged with ``site``."""
        if self.uses <= 0:
            raise AssertionError(f"inlining template of {self.decl.name} used more often than it is called")
        self.uses -= 1
        # nodes that share a location (an expression and its first operand) share its tagged
        # copy too: locations are immutable
        tagged: dict[int, tuple] = {}  # id(loc) -> (loc, kept alive so its id stays its own; copy)

        def tag(loc):
            pair = tagged.get(id(loc))
            if pair is None:
                pair = tagged[id(loc)] = (loc, with_chain(loc, site))
            return pair[1]

        if self.uses > 0:
            body = clone(self.decl.body, tag)
        else:   # the function is no longer called: its definition goes (the inliner prunes it)
            body = self.decl.body
            self.decl.body = A.Compound([], loc=body.loc)
            for n in walk(body, decl_types=False):
                if n.loc is not None:
                    n.loc = tag(n.loc)
        body.stmts = _convert_returns(body.stmts, self.is_void, self.needs_flag)
        return body


def _stmt_children(s: A.Node):
    if isinstance(s, A.Compound):
        return s.stmts
    return [sub for _, sub in A.branches(s)]


class _Returns(NodeVisitor):
    """Whether a statement holds a ``return`` (``in_loops``: one inside a loop or ``switch``)."""

    def __init__(self, in_loops: bool):
        self.in_loops = in_loops

    def visit_Return(self, s, inside: bool = False) -> bool:
        return inside or not self.in_loops

    def generic_visit(self, s, inside: bool = False) -> bool:
        return any(self.visit(c, inside) for c in _stmt_children(s))

    def visit_For(self, s, inside: bool = False) -> bool:
        return self.generic_visit(s, True)

    visit_While = visit_DoWhile = visit_Switch = visit_For


class _Continues(NodeVisitor):
    """Whether a loop body holds a ``continue`` of that loop."""

    def visit_Continue(self, s) -> bool:
        return True

    def visit_For(self, s) -> bool:
        return False

    visit_While = visit_DoWhile = visit_For

    def generic_visit(self, s) -> bool:
        return any(self.visit(c) for c in _stmt_children(s))


_returns_in_loops = _Returns(in_loops=True).visit
_has_return = _Returns(in_loops=False).visit
_has_continue = _Continues().visit


class _ConvertReturns(NodeVisitor):
    """A body's ``return``s as assignments to the result (and, with ``needs_flag``, the live flag
    cleared and what follows guarded by it): visiting a statement returns its conversion."""

    def __init__(self, is_void: bool, needs_flag: bool):
        self.is_void, self.needs_flag = is_void, needs_flag

    def block(self, stmts: list) -> list:
        out: list = []
        for i, s in enumerate(stmts):
            if not _has_return(s):
                out.append(s)
                continue
            if isinstance(s, A.Return):
                if s.expr is not None and not self.is_void:
                    out.append(assign(_RET, s.expr, s.loc))
                if self.needs_flag:
                    out.append(assign(_LIVE, A.BoolLit(False, loc=s.loc), s.loc))
                return out          # the rest of this block is dead code
            out.append(self.visit(s))
            rest = stmts[i + 1:]
            if rest:
                out.append(A.If(A.Ident(_LIVE, loc=s.loc), A.Compound(
                    self.block(rest), loc=s.loc), loc=s.loc))
            return out
        return out

    def visit_Compound(self, s: A.Compound) -> A.Compound:
        return A.Compound(self.block(s.stmts), loc=s.loc)

    def visit_If(self, s: A.If) -> A.If:
        def branch(b):
            if b is None:
                return None
            stmts = b.stmts if isinstance(b, A.Compound) else [b]
            return A.Compound(self.block(stmts), loc=b.loc)
        return A.If(s.cond, branch(s.then), branch(s.else_), loc=s.loc)

    def visit_Return(self, s: A.Return) -> A.Compound:
        return A.Compound(self.block([s]), loc=s.loc)

    def generic_visit(self, s):
        raise AssertionError("returns inside loops are not inlined")


def _convert_returns(stmts: list, is_void: bool, needs_flag: bool) -> list:
    return _ConvertReturns(is_void, needs_flag).block(stmts)


def _statements(body: A.Stmt):
    """Every statement under ``body`` (itself included), without recursion."""
    stack = [body]
    while stack:
        s = stack.pop()
        yield s
        if isinstance(s, A.Compound):
            stack.extend(reversed(s.stmts))
            continue
        stack.extend(sub for _, sub in reversed(A.branches(s)))
        if isinstance(s, A.For) and s.init is not None:
            stack.append(s.init)


def _wrap(stmts: list, loc) -> A.Stmt:
    return stmts[0] if len(stmts) == 1 else A.Compound(stmts, loc=loc)


class _Inliner(NodeVisitor):
    """Visiting a statement returns the statements that replace it; visiting an expression
    that holds a call to inline (through :meth:`expr`) appends to ``pre`` what must run before
    it and returns what stands in its place."""

    def __init__(self, unit: A.TranslationUnit):
        self.unit = clone(unit)
        self.names = NameAllocator(unit)
        # original FunctionDecl (call targets) -> its copy in self.unit
        self.copy_of = {id(o): c for o, c in zip(unit.decls, self.unit.decls)
                        if isinstance(o, A.FunctionDecl)}
        # original global declaration (what a global Symbol's ``decl`` is) -> its copy
        self.global_copy = {id(o): c for o, c in zip(unit.decls, self.unit.decls)
                            if not isinstance(o, A.FunctionDecl)}
        self.defs = [d for d in self.unit.decls if isinstance(d, A.FunctionDecl) and d.body]
        self.templates: dict[int, _Template] = {}
        self.inlinable: dict[int, bool] = {}
        self.effectful: dict[int, bool] = {}
        self._calls_memo: dict[int, tuple] = {}
        # the statement being lowered when identical calls in it may share one inlined body,
        # and the results made so far: (id(pre), share key) -> (pre, result name)
        self.sharing: Optional[A.Stmt] = None
        self.shared: dict[tuple, tuple] = {}
        self._effects_memo: dict[int, tuple] = {}

    # ------------------------------------------------------------------ driver
    def run(self) -> A.TranslationUnit:
        self.call_sites: dict[int, int] = {}
        for d in self.defs:
            for n in walk(d.body, decl_types=False):
                if isinstance(n, A.Call):
                    t = self._target(n)
                    if t is not None:
                        self.call_sites[id(t)] = self.call_sites.get(id(t), 0) + 1
        for d in self.defs:
            self.inlinable[id(d)] = d.name != "main" and not _returns_in_loops(d.body)
        self._unshadow_globals()
        for d in self._callees_first():
            self._process(d)
        self._prune()
        self._define_after_globals()
        self._declare_before_use()
        return self.unit

    def _declare_before_use(self) -> None:
        """Give a function the inliner kept a prototype before its first use where its
        definition now stands after a function calling it: a call inlined from a body defined
        later (``void mainImage(out vec4 c, vec2 p);`` declared first, ``main`` calling it,
        ``mainImage`` calling a helper that returns from inside a loop, so kept: the call of the
        helper moves into ``main``, before the helper's definition, and ``mainImage``'s prototype
        goes with ``mainImage``)."""
        seen: set = set()
        out: list = []
        for d in self.unit.decls:
            if isinstance(d, A.FunctionDecl):
                if d.body is not None:
                    for n in walk(d.body, decl_types=False):
                        if n.__class__ is not A.Call:
                            continue
                        t = self._target(n)
                        if t is not None and t is not d and _signature(t) not in seen:
                            seen.add(_signature(t))
                            out.append(A.FunctionDecl(t.return_type, t.name, clone(t.params),
                                                      None, loc=t.loc))
                seen.add(_signature(d))
            out.append(d)
        self.unit.decls = out

    def _global_names_read(self, d: A.FunctionDecl) -> set[str]:
        """The global names the body of ``d`` uses: globals (by their semantic symbols) and the
        functions it calls (built-in or not)."""
        names = {n.name for n in walk(d.body, decl_types=False) if n.__class__ is A.Ident
                 and n.symbol is not None and id(getattr(n.symbol, "decl", None)) in self.global_copy}
        names.update(n.name for n in walk(d.body, decl_types=False) if n.__class__ is A.Call
                     and n.kind in ("builtin", "function"))
        return names

    def _unshadow_globals(self) -> None:
        """Rename the locals and parameters that have the name of a global or a function some
        inlinable function uses: once that function's body is inlined into their scope, the
        name would mean the local (``vec3 pos; float f() { return pos.y; }`` inlined where
        ``float pos`` is declared; ``step(a, b)`` inlined where ``float step`` is). Each gets
        a fresh ``_rr_<name>_<n>``; other names are left as written."""
        shadowed = set()
        for d in self.defs:
            if self.inlinable[id(d)]:
                shadowed |= self._global_names_read(d)
        if not shadowed:
            return
        for d in self.defs:
            params = [p for p in d.params if p.name in shadowed]
            if not params and not any(isinstance(n, A.Declarator) and n.name in shadowed
                                      for n in walk(d.body, decl_types=False)):
                continue
            initial = {}
            for p in params:
                initial[p.name] = p.name = self.names.fresh(p.name)
            rewrite_scoped(d.body, initial,
                           lambda name: self.names.fresh(name) if name in shadowed else None)

    def _define_after_globals(self) -> None:
        """Move a function definition that now uses a global declared after it (a body
        inlined from a function defined later: ``float f(); void main() { ... f() ... }
        float k; float f() { return k; }``; a variable, or a struct type) to right after the
        last such declaration, leaving a prototype in its place (none for ``main``)."""
        decls = self.unit.decls
        defs = [i for i, x in enumerate(decls) if isinstance(x, A.FunctionDecl) and x.body is not None]
        if not defs or not any(not isinstance(x, A.FunctionDecl) for x in decls[defs[0] + 1:]):
            return   # every global is declared before the first definition (the usual layout)
        pos = {id(x): i for i, x in enumerate(decls)}
        struct_pos = {x.type.spec.struct.name: i for i, x in enumerate(decls)
                      if isinstance(x, A.VariableDecl) and x.type.spec.struct is not None
                      and x.type.spec.struct.name}
        after: dict[int, list] = {}
        moved: dict[int, A.FunctionDecl] = {}
        for i, d in enumerate(decls):
            if not isinstance(d, A.FunctionDecl) or d.body is None:
                continue
            last = max([pos.get(id(self.global_copy[id(n.symbol.decl)]), -1)
                        for n in walk(d.body) if n.__class__ is A.Ident and n.symbol is not None
                        and id(getattr(n.symbol, "decl", None)) in self.global_copy]
                       + [struct_pos[n.name] for n in walk(d.body)
                          if n.__class__ in (A.TypeSpecifier, A.Call) and n.name in struct_pos],
                       default=-1)
            if last > i:
                after.setdefault(id(decls[last]), []).append(d)
                moved[id(d)] = d
        if not moved:
            return
        out = []
        for x in decls:
            if id(x) in moved:
                if x.name != "main":
                    out.append(A.FunctionDecl(x.return_type, x.name, clone(x.params), None,
                                              loc=x.loc))
            else:
                out.append(x)
            out.extend(after.get(id(x), ()))
        self.unit.decls = out

    def _target(self, call: A.Call) -> Optional[A.FunctionDecl]:
        if call.kind != "function" or not isinstance(call.target, A.FunctionDecl):
            return None
        return self.copy_of.get(id(call.target), call.target if call.target.body else None)

    def _callees_first(self) -> list:
        """Every definition after the functions it calls (without recursion: a chain of
        thousands of functions is fine), each function's effects found on the way; refuses a
        program whose inlining would copy more syntax nodes than the analysis budget."""
        order: list = []
        state: dict[int, int] = {}
        for root in self.defs:
            stack = [(root, False)]
            while stack:
                d, done = stack.pop()
                if done:
                    order.append(d)
                    state[id(d)] = 2
                    self.effectful[id(d)] = self._body_effectful(d)
                    continue
                if state.get(id(d)):
                    continue
                state[id(d)] = 1
                stack.append((d, True))
                for n in walk(d.body, decl_types=False):
                    if n.__class__ is A.Call:
                        t = self._target(n)
                        if t is not None and not state.get(id(t)):
                            stack.append((t, False))
        self._check_copies(order)
        return order

    def _check_copies(self, order: list) -> None:
        """The syntax nodes the call sites will copy (each inlined call copies its callee's body,
        its own calls inlined; calls shared as :meth:`inline` shares them count once), checked
        against ``budget.analysis_nodes`` before any is made."""
        size: dict[int, int] = {}
        depth: dict[int, tuple] = {}
        copies = 0
        for d in order:
            own, extra, deepest = 0, 0, (0, None)
            seen: set = set()
            for stmt in _statements(d.body):
                shareable = self._shareable(stmt)
                for part in A.own_parts(stmt):
                    for n in walk(part, decl_types=False):
                        own += 1
                        t = self._target(n) if n.__class__ is A.Call else None
                        if t is None or not self.inlinable.get(id(t), False):
                            continue
                        key = self._share_key(stmt, t, n.args) if shareable else None
                        if key is not None and key in seen:
                            continue
                        seen.add(key)
                        extra += size[id(t)]
                        if depth[id(t)][0] + 1 > deepest[0]:
                            deepest = (depth[id(t)][0] + 1, t)
            size[id(d)] = own + extra
            depth[id(d)] = deepest
            copies += extra
        if copies <= budget.analysis_nodes:
            return
        d = max(order, key=lambda x: (depth[id(x)][0], x.name == "main"))
        chain = [d.name]
        t = depth[id(d)][1]
        while t is not None:
            chain.append(t.name)
            t = depth[id(t)][1]
        shown = " → ".join(chain[:3] + (["…"] if len(chain) > 4 else []) + chain[3:][-1:])
        amount = f"{copies:,}" if copies < 10 ** 15 else f"about 10^{len(str(copies)) - 1}"
        raise GLSLError(
            f"inlining the function calls would copy {amount} syntax nodes (calls nested "
            f"{len(chain) - 1:,} deep: {shown}), more than the analysis budget of "
            f"{budget.analysis_nodes:,}", d.loc,
            "raise it with 'rrcache --max-ast-nodes N ...' if the machine has the memory, or call "
            "the deepest functions fewer times")

    def _shareable(self, stmt) -> bool:
        """Whether identical calls of a function without effects in ``stmt`` may share one
        inlined body: nothing the statement evaluates has an effect (but its assignment)."""
        if isinstance(stmt, A.ExprStmt) and isinstance(stmt.expr, A.Assign) and stmt.expr.op == "=":
            return not self.has_effects(stmt.expr.value)
        return not any(self.has_effects(p) for p in A.own_parts(stmt))

    def _share_key(self, stmt, fd: A.FunctionDecl, args: list) -> Optional[tuple]:
        """What two calls must have alike to share one inlined body: the statement, the function
        (one without effects) and the arguments as printed."""
        if self.effectful.get(id(fd), True):
            return None
        return (id(stmt), id(fd), tuple(print_expr(a) for a in args))

    def _process(self, d: A.FunctionDecl) -> None:
        """Inline the calls in ``d`` (its callees are done); make its template."""
        d.body = A.Compound(self.block(d.body.stmts), loc=d.body.loc)
        if self.inlinable[id(d)]:
            stmts = d.body.stmts
            last_only = all(not _has_return(s) for s in stmts[:-1]) and (
                not stmts or isinstance(stmts[-1], A.Return) or not _has_return(stmts[-1]))
            self.templates[id(d)] = _Template(d, not last_only, self.call_sites.get(id(d), 0))

    def _body_effectful(self, d: A.FunctionDecl) -> bool:
        """Whether calling ``d`` has an effect beyond its result: it has an ``out``/``inout``
        parameter, writes a variable that is not its own, or calls something effectful."""
        if any(param_qualifier(p) != "in" for p in d.params):
            return True
        for n in walk(d.body, decl_types=False):
            if n.__class__ is A.Call:
                t = self._target(n)
                if t is not None and self.effectful.get(id(t), True):
                    return True
                if n.kind == "builtin" and getattr(n.target, "side_effects", False):
                    return True
        return any(w.root.symbol is None or w.root.symbol.kind not in ("local", "param")
                   for w in definitions(d.body))

    def _prune(self) -> None:
        """Drop functions (and prototypes) no longer called from main or a kept function."""
        by_name: dict[str, list[A.FunctionDecl]] = {}
        for d in self.defs:
            by_name.setdefault(d.name, []).append(d)
        keep: set[int] = set()
        stack = [d for d in self.defs if d.name == "main"]
        roots = [x for x in self.unit.decls if not isinstance(x, A.FunctionDecl)]
        for r in roots:
            for n in walk(r, decl_types=False):
                if isinstance(n, A.Call) and n.name in by_name:
                    stack.extend(by_name[n.name])
        while stack:
            d = stack.pop()
            if id(d) in keep:
                continue
            keep.add(id(d))
            for n in walk(d.body, decl_types=False):
                if isinstance(n, A.Call) and n.name in by_name:
                    stack.extend(by_name[n.name])
        kept_names = {d.name for d in self.defs if id(d) in keep}
        decls = []
        for x in self.unit.decls:
            if isinstance(x, A.FunctionDecl):
                if x.body is not None and id(x) not in keep:
                    continue
                if x.body is None and x.name not in kept_names:
                    continue
            decls.append(x)
        self.unit.decls = decls

    # ------------------------------------------------------------------ predicates
    def has_call(self, e) -> bool:
        """Whether the expression contains a call that will be inlined."""
        if e is None or not isinstance(e, A.Node):
            return False
        key = id(e)
        got = self._calls_memo.get(key, (None, None))[1]
        if got is None:
            got = False
            if isinstance(e, A.Call):
                t = self._target(e)
                got = t is not None and self.inlinable.get(id(t), False)
            if not got:
                got = any(self.has_call(c) for c in children(e, decl_types=False))
            self._calls_memo[key] = (e, got)
        return got

    def has_effects(self, e) -> bool:
        """Whether evaluating the expression has side effects."""
        if e is None:
            return False
        key = id(e)
        got = self._effects_memo.get(key, (None, None))[1]
        if got is None:
            if isinstance(e, A.Assign) or (isinstance(e, A.Unary) and e.op in ("++", "--")):
                got = True
            elif isinstance(e, A.Call) and (
                    (self._target(e) is not None and self.effectful.get(id(self._target(e)), True))
                    or getattr(e.target, "side_effects", False)):
                got = True
            else:
                got = any(self.has_effects(c) for c in children(e, decl_types=False))
            self._effects_memo[key] = (e, got)
        return got

    # ------------------------------------------------------------------ statements
    def block(self, stmts: list) -> list:
        out: list = []
        for s in stmts:
            out.extend(self.stmt(s))
        return out

    def stmt(self, s) -> list:
        saved = self.sharing
        self.sharing = s if self._shareable(s) else None
        try:
            return self.visit(s)
        finally:
            self.sharing = saved

    def generic_visit(self, s, *args):
        return [s]

    def visit_Compound(self, s: A.Compound) -> list:
        return [A.Compound(self.block(s.stmts), loc=s.loc)]

    def visit_DeclStmt(self, s: A.DeclStmt) -> list:
        return self.decl_stmt(s)

    def visit_ExprStmt(self, s: A.ExprStmt) -> list:
        if not self.has_call(s.expr):
            return [s]
        pre: list = []
        e = self.expr(s.expr, pre, value_used=False)
        return pre + ([A.ExprStmt(e, loc=s.loc)] if e is not None else [])

    def visit_If(self, s: A.If) -> list:
        pre: list = []
        cond = self.expr(s.cond, pre)
        then = _wrap(self.stmt(s.then), s.then.loc)
        else_ = _wrap(self.stmt(s.else_), s.else_.loc) if s.else_ is not None else None
        return pre + [A.If(cond, then, else_, loc=s.loc)]

    def visit_Switch(self, s: A.Switch) -> list:
        pre: list = []
        e = self.expr(s.expr, pre)
        return pre + [A.Switch(e, A.Compound(self.block(s.body.stmts), loc=s.body.loc),
                               loc=s.loc)]

    def visit_Return(self, s: A.Return) -> list:
        pre: list = []
        e = self.expr(s.expr, pre) if s.expr is not None else None
        return pre + [A.Return(e, loc=s.loc)]

    def visit_For(self, s: A.For) -> list:
        return self.for_stmt(s)

    def visit_While(self, s: A.While) -> list:
        body = _wrap(self.stmt(s.body), s.body.loc)
        if isinstance(s.cond, A.Expr) and self.has_call(s.cond):
            pre: list = []
            cond = self.expr(s.cond, pre)
            body = A.Compound(pre + [self._exit_unless(cond), body], loc=s.loc)
            return [A.While(A.BoolLit(True, loc=s.loc), body, loc=s.loc)]
        return [A.While(s.cond, body, loc=s.loc)]

    def visit_DoWhile(self, s: A.DoWhile) -> list:
        body = _wrap(self.stmt(s.body), s.body.loc)
        if self.has_call(s.cond) and not _has_continue(s.body):
            pre: list = []
            cond = self.expr(s.cond, pre)
            return [A.DoWhile(A.Compound([body] + pre, loc=s.loc), cond, loc=s.loc)]
        return [A.DoWhile(body, s.cond, loc=s.loc)]

    def _exit_unless(self, cond: A.Expr) -> A.If:
        return A.If(A.Unary("!", cond, loc=cond.loc), A.Break(loc=cond.loc), loc=cond.loc)

    def decl_stmt(self, s: A.DeclStmt) -> list:
        decl = s.decl
        if not isinstance(decl, A.VariableDecl) or not any(
                self.has_call(d.init) for d in decl.declarators):
            return [s]
        out: list = []
        for i, d in enumerate(decl.declarators):
            pre: list = []
            if d.init is not None:
                d.init = self.expr(d.init, pre)
            full = decl.type
            if i > 0 and full.spec.struct is not None and full.spec.struct.name:
                full = A.FullType(full.qualifiers, A.TypeSpecifier(full.spec.struct.name),
                                  loc=full.loc)
            out += pre + [A.DeclStmt(A.VariableDecl(full, [d], loc=decl.loc), loc=s.loc)]
        return out

    def for_stmt(self, s: A.For) -> list:
        pre_init: list = []
        init = s.init
        if init is not None:
            lowered = self.stmt(init)
            pre_init, init = lowered[:-1], lowered[-1]
        body = _wrap(self.stmt(s.body), s.body.loc)
        cond, step = s.cond, s.step
        if isinstance(cond, A.Expr) and self.has_call(cond):
            pre: list = []
            c = self.expr(cond, pre)
            body = A.Compound(pre + [self._exit_unless(c), body], loc=s.loc)
            cond = None
        if step is not None and self.has_call(step) and not _has_continue(s.body):
            pre = []
            e = self.expr(step, pre, value_used=False)
            body = A.Compound([body] + pre + ([A.ExprStmt(e, loc=step.loc)] if e else []),
                              loc=s.loc)
            step = None
        loop = A.For(init, cond, step, body, loc=s.loc)
        if pre_init:
            return [A.Compound(pre_init + [loop], loc=s.loc)]
        return [loop]

    # ------------------------------------------------------------------ expressions
    def hoist(self, e: A.Expr, pre: list) -> A.Expr:
        """Evaluate ``e`` now, into a fresh temporary (a sampler or an image stays as it is: GLSL
        has no local variables of those types)."""
        if is_literal(e) or e.type is None or getattr(e, "_rr_temp", False) or holds_opaque(e.type):
            return e
        name = self.names.fresh("t")
        pre.append(declare_typed(name, e.type, e, e.loc))
        ident = A.Ident(name, loc=e.loc, type=e.type)
        ident._rr_temp = True
        return ident

    def expr(self, e, pre: list, value_used: bool = True):
        if e is None or not self.has_call(e):
            return e
        return self.visit(e, pre, value_used)

    def visit_Call(self, e: A.Call, pre: list, value_used: bool = True):
        t = self._target(e)
        if t is not None and self.inlinable.get(id(t), False):
            return self.inline(e, t, pre)
        e.args = self.operands(e.args, pre, _lvalue_positions(e))
        return e

    def visit_Binary(self, e: A.Binary, pre: list, value_used: bool = True):
        if e.op not in ("&&", "||"):
            return self.visit_Expr(e, pre, value_used)
        left = self.expr(e.left, pre)
        if not self.has_call(e.right):
            e.left = left
            return e
        name = self.names.fresh("cond")
        pre.append(declare(name, A.FullType([], A.TypeSpecifier("bool")), left, loc=e.loc))
        inner: list = []
        right = self.expr(e.right, inner)
        inner.append(assign(name, right, e.loc))
        test = A.Ident(name, loc=e.loc)
        if e.op == "||":
            test = A.Unary("!", test, loc=e.loc)
        pre.append(A.If(test, A.Compound(inner, loc=e.loc), loc=e.loc))
        return A.Ident(name, loc=e.loc, type=e.type)

    def visit_Ternary(self, e: A.Ternary, pre: list, value_used: bool = True):
        cond = self.expr(e.cond, pre)
        if not (self.has_call(e.then) or self.has_call(e.else_)):
            e.cond = cond
            return e
        if e.type is not None and e.type.is_void:   # ``c ? f() : g();`` as a statement
            arms = []
            for branch in (e.then, e.else_):
                inner: list = []
                v = self.expr(branch, inner, value_used=False)
                if v is not None:
                    inner.append(A.ExprStmt(v, loc=branch.loc))
                arms.append(A.Compound(inner, loc=e.loc))
            pre.append(A.If(cond, arms[0], arms[1], loc=e.loc))
            return None
        name = self.names.fresh("sel")
        pre.append(declare_typed(name, e.type, None, e.loc))
        branches = []
        for branch in (e.then, e.else_):
            inner = []
            v = self.expr(branch, inner)
            inner.append(assign(name, v, e.loc))
            branches.append(A.Compound(inner, loc=e.loc))
        pre.append(A.If(cond, branches[0], branches[1], loc=e.loc))
        return A.Ident(name, loc=e.loc, type=e.type)

    def visit_Sequence(self, e: A.Sequence, pre: list, value_used: bool = True):
        for x in e.exprs[:-1]:
            v = self.expr(x, pre, value_used=False)
            if v is not None:
                pre.append(A.ExprStmt(v, loc=x.loc))
        return self.expr(e.exprs[-1], pre, value_used)

    def visit_Assign(self, e: A.Assign, pre: list, value_used: bool = True):
        e.target = self.lvalue(e.target, pre)
        e.value = self.expr(e.value, pre)
        return e

    def visit_Unary(self, e: A.Unary, pre: list, value_used: bool = True):
        if e.op not in ("++", "--"):
            return self.visit_Expr(e, pre, value_used)
        e.operand = self.lvalue(e.operand, pre)
        return e

    def visit_InitList(self, e: A.InitList, pre: list, value_used: bool = True):
        e.items = self.operands(e.items, pre, set())
        return e

    def visit_Expr(self, e, pre: list, value_used: bool = True):
        """An operation on its operands (fields, indices, arithmetic): they are lowered left to
        right."""
        names = A.child_fields(e.__class__, decl_types=False)
        values = self.operands([getattr(e, n) for n in names], pre, set())
        for n, v in zip(names, values):
            setattr(e, n, v)
        return e

    def operands(self, items: list, pre: list, lvalues: set) -> list:
        """Lower operands evaluated left to right, keeping the order of side effects."""
        out: list = []
        for j, item in enumerate(items):
            if j in lvalues:
                out.append(self.lvalue(item, pre))
                continue
            if self.has_call(item):
                if self._effects_call(item) or any(
                        self.has_effects(x) for k, x in enumerate(out) if k not in lvalues):
                    out = [x if k in lvalues else self.hoist(x, pre) for k, x in enumerate(out)]
                out.append(self.expr(item, pre))
            else:
                out.append(item)
        return out

    def _effects_call(self, e) -> bool:
        for n in walk(e, decl_types=False):
            if isinstance(n, A.Call):
                t = self._target(n)
                if t is not None and self.effectful.get(id(t), True):
                    return True
        return False

    def lvalue(self, e: A.Expr, pre: list) -> A.Expr:
        """An l-value whose index expressions are evaluated once, now."""
        if isinstance(e, (A.Field, A.Index)):
            e.obj = self.lvalue(e.obj, pre)
            if isinstance(e, A.Index):
                idx = self.expr(e.index, pre)
                e.index = idx if is_literal(idx) else self.hoist(idx, pre)
        return e

    # ------------------------------------------------------------------ the call site
    def inline(self, call: A.Call, fd: A.FunctionDecl, pre: list) -> Optional[A.Expr]:
        quals = [param_qualifier(p) for p in fd.params]
        args = self.operands(call.args, pre, {i for i, q in enumerate(quals) if q != "in"})
        tpl = self.templates[id(fd)]
        site = f"{fd.name} ({call.loc.line}:{call.loc.col})" if call.loc else fd.name
        is_void = fd.return_type.spec.name == "void"
        key = None
        if self.sharing is not None and not is_void:
            key = self._share_key(self.sharing, fd, args)
            got = self.shared.get((id(pre), key)) if key is not None else None
            if got is not None and got[0] is pre:   # f(x) again, with nothing changed: its value
                tpl.release()
                return A.Ident(got[1], loc=call.loc, type=call.type)
        mapping: dict = {}
        ret = None
        if not is_void:
            ret = self.names.fresh(fd.name)
            if key is not None:
                self.shared[(id(pre), key)] = (pre, ret)
            rtype = A.FullType([q for q in fd.return_type.qualifiers
                                if q in ("lowp", "mediump", "highp")], fd.return_type.spec,
                               loc=fd.return_type.loc)
            pre.append(declare(ret, rtype, None, None, call.loc))
            mapping[_RET] = ret
        block: list = []
        writebacks: list = []
        for p, arg, q in zip(fd.params, args, quals):
            if holds_opaque(arg.type):
                # a sampler, image or atomic counter (or a struct holding one) cannot be copied
                # into a local: the argument itself stands for the parameter in the body (an
                # index into an array of samplers stays as written: GLSL 3.30 wants a constant)
                if self.has_effects(arg):
                    raise UnsupportedShaderError(
                        f"the {arg.type} argument of '{fd.name}' has a side effect", arg.loc,
                        "compute the index before the call")
                if p.name:
                    mapping[p.name] = _substitute(arg)
                continue
            name = self.names.fresh(p.name or "arg")
            if p.name:
                mapping[p.name] = name
            keep = [x for x in p.type.qualifiers
                    if not (isinstance(x, str) and x in ("in", "out", "inout", "const"))]
            ptype = A.FullType(keep, p.type.spec, loc=p.type.loc)
            dims = clone(p.array_dims) if p.array_dims else None
            block.append(declare(name, ptype, arg if q != "out" else None, dims, call.loc))
            if q != "in":
                writebacks.append(A.ExprStmt(
                    A.Assign("=", clone(arg), A.Ident(name, loc=call.loc), loc=call.loc),
                    loc=call.loc))
        if tpl.needs_flag:
            live = self.names.fresh("live")
            mapping[_LIVE] = live
            block.append(declare(live, A.FullType([], A.TypeSpecifier("bool")),
                                 A.BoolLit(True, loc=call.loc), loc=call.loc))
        body = tpl.instantiate(site)
        rewrite_scoped(body, mapping, self.names.fresh)
        block += body.stmts + writebacks
        pre.append(A.Compound(block, loc=call.loc))
        if ret is None:
            return None
        return A.Ident(ret, loc=call.loc, type=call.type)


def _signature(d: A.FunctionDecl) -> tuple:
    """A function's name and parameter types as written (what tells overloads apart)."""
    return (d.name,) + tuple((p.type.spec.name, p.type.spec.struct is not None,
                              len(p.array_dims or ()) + len(p.type.spec.array_dims or ()))
                             for p in d.params)


def holds_opaque(t) -> bool:
    """Whether a value of type ``t`` is or holds an opaque type (a sampler, an image, an atomic
    counter), which GLSL allows only as uniforms and parameters."""
    if t is None:
        return False
    if t.is_opaque:
        return True
    return t.base == "struct" and any(holds_opaque(ft) for _, ft in (t.fields or ()))


def _substitute(arg: A.Expr):
    """A replacement for every use of a parameter: a copy of the argument."""
    return lambda ident: clone(arg)


def _lvalue_positions(call: A.Call) -> set:
    return {i for i, q in enumerate(out_qualifiers(call)) if q != "in"}

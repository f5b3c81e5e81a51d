"""Pass: dead-code elimination of a checked translation unit.

Each emitted pass is a copy of the whole shader with some outputs gone; this pass removes what no
longer contributes, so that every shader holds only what its pass needs.

``main`` — backward liveness over the structured tree, at variable granularity (variables are
told apart by their declaration, so shadowing is handled):

- live at the end of ``main`` (and at every ``return``): the observable outputs, i.e. the
  ``out`` globals and the built-in outputs (``gl_FragDepth``...) — the roots;
- a statement is kept when it writes a live variable (any component), has an effect beyond
  variables (a side-effecting built-in, a call of a function that discards), is a ``discard``
  or a ``return``, or is control flow that contains kept statements (whose conditions then
  become live: control dependence);
- a full assignment ``x = e`` kills ``x``; partial ones (``x.y = e``, ``x[i] = e``) do not;
- loops that remain after unrolling are solved to a fixed point; ``break``/``continue`` are kept
  when their loop or ``switch`` is, without keeping it alive by themselves;
- a declaration whose variable is dead right after it loses its initialiser, and disappears
  when nothing references the variable any more;
- what is left is tidied (:func:`tidy_blocks`): blocks left empty are removed, and a block
  whose only statement is a block (inlined calls and unrolled iterations whose other statements
  went) becomes that block, so no pass shows runs of nested braces; ``case`` labels left at the
  end of a ``switch`` with no statement after them are removed (a label must precede a
  statement).

Globals — from ``main`` and the declarations in ``keep`` (the runtime's snippets), everything
referenced by name is kept, transitively: functions (and prototypes), uniforms, samplers,
``in``/``out`` variables, constants, struct types, interface blocks. The rest is removed.

>>> from rrcache.glsl.parser import parse_source
>>> from rrcache.glsl.semantic import check
>>> from rrcache.glsl.printer import print_glsl
>>> unit = parse_source("#version 330\\nuniform float a; uniform float b; out vec4 c;\\n"
...                     "void main() { float x = a; float y = b; c = vec4(x); }")
>>> _ = check(unit)
>>> print(print_glsl(prune(unit)), end="")
#version 330 core
uniform float a;
out vec4 c;
<BLANKLINE>
void main()
{
    float x = a;
    c = vec4(x);
}
"""
from __future__ import annotations

from typing import Iterable, Optional

from rrcache.glsl import ast as A
from rrcache.glsl.ast import main_function, walk
from rrcache.glsl.defuse import definitions, uses, var_key
from rrcache.glsl.visitor import NodeVisitor

DEAD, CONTROL, ESSENTIAL = 0, 1, 2


def _global(ident: A.Ident) -> bool:
    """Whether an identifier names something other than a local variable or a parameter."""
    return ident.symbol is not None and ident.symbol.kind not in ("local", "param")


def _observable(ident: A.Ident) -> bool:
    sym = ident.symbol
    if sym is None:
        return False
    return sym.kind == "out" or (sym.kind == "builtin" and "out" in sym.qualifiers)


class _Loop:
    def __init__(self, brk: set, cont: Optional[set]):
        self.brk = brk
        self.cont = cont


class _Effects:
    __slots__ = ("reads", "writes", "kills", "essential")

    def __init__(self):
        self.reads: set = set()
        self.writes: set = set()
        self.kills: set = set()
        self.essential = False


class _Liveness(NodeVisitor):
    """Visiting a statement with the variables live after it returns ``(live before, status)``."""

    def __init__(self, unit: A.TranslationUnit, main: A.FunctionDecl):
        self.functions = {}
        for d in unit.decls:
            if isinstance(d, A.FunctionDecl) and d.body is not None:
                self.functions.setdefault(d.name, []).append(d)
        self.summaries: dict[str, _Effects] = {}
        self.observable = {var_key(n) for n in walk(main.body)
                           if isinstance(n, A.Ident) and _observable(n)}
        self.status: dict[int, int] = {}
        self.live_decl: dict[int, bool] = {}
        self.loops: list[_Loop] = []
        # False while deciding whether a loop has essential work: the conditions of control
        # statements (``if (c) break;``) and of the loop itself then read nothing, so that a
        # loop whose only work feeds its own control is found dead.
        self.control_reads = True

    # ----------------------------------------------------------------------- effects

    def function_summary(self, name: str) -> _Effects:
        """Globals read/written by the user function ``name`` (all overloads, transitively)."""
        found = self.summaries.get(name)
        if found is not None:
            return found
        eff = _Effects()
        self.summaries[name] = eff  # GLSL has no recursion; this also stops a malformed cycle
        for fd in self.functions.get(name, []):
            for n in walk(fd.body):
                if n.__class__ is A.Discard:
                    eff.essential = True
                elif n.__class__ is A.Call:
                    self._call_effects(n, eff)
            eff.reads |= {var_key(n) for n in walk(fd.body) if n.__class__ is A.Ident
                          and _global(n)}
            eff.writes |= {var_key(d.root) for d in definitions(fd.body) if _global(d.root)}
        return eff

    def _call_effects(self, call: A.Call, eff: _Effects) -> None:
        if call.kind == "function" or isinstance(call.target, A.FunctionDecl):
            summary = self.function_summary(call.name)
            eff.reads |= summary.reads
            eff.writes |= summary.writes
            eff.essential = eff.essential or summary.essential
        elif getattr(call.target, "side_effects", False):
            eff.essential = True

    def effects(self, node: Optional[A.Node]) -> _Effects:
        eff = _Effects()
        if node is None:
            return eff
        if isinstance(node, A.Assign) and node.op == "=" and isinstance(node.target, A.Ident):
            eff.kills.add(var_key(node.target))
        for n in walk(node):
            if n.__class__ is A.Call:
                self._call_effects(n, eff)
        eff.reads.update(var_key(n) for n in uses(node))
        eff.writes.update(var_key(d.root) for d in definitions(node))
        return eff

    # ----------------------------------------------------------------------- statements

    def block(self, stmts: list, live: set) -> tuple[set, int]:
        status = DEAD
        for s in reversed(stmts):
            live, st = self.stmt(s, live)
            status = max(status, st)
        return live, status

    def stmt(self, s: A.Stmt, live: set) -> tuple[set, int]:
        live_in, st = self.visit(s, set(live))
        self.status[id(s)] = st
        return live_in, st

    def visit_Compound(self, s: A.Compound, live: set) -> tuple[set, int]:
        return self.block(s.stmts, live)

    def visit_ExprStmt(self, s: A.ExprStmt, live: set) -> tuple[set, int]:
        if s.expr is None:
            return live, DEAD
        eff = self.effects(s.expr)
        if eff.essential or eff.writes & live:
            return (live - eff.kills) | eff.reads, ESSENTIAL
        return live, DEAD

    def visit_DeclStmt(self, s: A.DeclStmt, live: set) -> tuple[set, int]:
        return self.decl(s.decl, live)

    def visit_If(self, s: A.If, live: set) -> tuple[set, int]:
        t_in, t_st = self.stmt(s.then, live)
        e_in, e_st = self.stmt(s.else_, live) if s.else_ is not None else (live, DEAD)
        eff = self.effects(s.cond)
        st = max(t_st, e_st)
        if eff.essential or eff.writes & live:
            st = ESSENTIAL
        if st == DEAD:
            return live, DEAD
        if st == CONTROL and not self.control_reads:
            return t_in | e_in, st
        return t_in | e_in | eff.reads, st

    def visit_Break(self, s: A.Break, live: set) -> tuple[set, int]:
        target = self.loops[-1].brk if self.loops else live
        return set(target), CONTROL

    def visit_Continue(self, s: A.Continue, live: set) -> tuple[set, int]:
        cont = next((lp.cont for lp in reversed(self.loops) if lp.cont is not None), None)
        return set(cont if cont is not None else live), CONTROL

    def visit_Return(self, s: A.Return, live: set) -> tuple[set, int]:
        return set(self.observable) | self.effects(s.expr).reads, ESSENTIAL

    def visit_Discard(self, s: A.Discard, live: set) -> tuple[set, int]:
        return set(), ESSENTIAL

    def generic_visit(self, s: A.Node, live: set) -> tuple[set, int]:
        return live, CONTROL  # a case label outside a switch body, or anything unforeseen

    def decl(self, decl, live: set) -> tuple[set, int]:
        if not isinstance(decl, A.VariableDecl) or not decl.declarators:
            return live, CONTROL  # local struct type or precision statement: kept
        any_live = False
        for d in reversed(decl.declarators):
            eff = _Effects()
            for part in [d.init] + list(d.array_dims or []):
                if part is not None:
                    sub = self.effects(part)
                    eff.reads |= sub.reads
                    eff.writes |= sub.writes
                    eff.essential = eff.essential or sub.essential
            key = (id(decl), d.name)
            alive = key in live or bool(eff.writes & live) or eff.essential
            self.live_decl[id(d)] = alive
            if alive:
                any_live = True
                live = (live - {key}) | eff.reads
        return live, ESSENTIAL if any_live else DEAD

    def _reads(self, cond) -> set:
        if isinstance(cond, A.VariableDecl):
            out = set()
            for d in cond.declarators:
                out |= self.effects(d.init).reads
            return out
        return self.effects(cond).reads

    def visit_For(self, s, live: set) -> tuple[set, int]:
        saved = self.control_reads
        self.control_reads = False
        try:
            _, st = self._loop(s, live)
        finally:
            self.control_reads = saved
        if st == DEAD:
            return live, DEAD
        return self._loop(s, live)

    def _loop(self, s, live: set) -> tuple[set, int]:
        cond_reads = self._reads(s.cond) if self.control_reads else set()
        step_reads = (self.effects(s.step).reads if isinstance(s, A.For) and self.control_reads
                      else set())
        head = set(live) | cond_reads
        ctx = _Loop(set(live), None)
        self.loops.append(ctx)
        try:
            while True:
                ctx.cont = step_reads | head
                body_in, body_st = self.stmt(s.body, ctx.cont)
                new_head = set(live) | cond_reads | body_in
                if new_head == head:
                    break
                head = new_head
        finally:
            self.loops.pop()
        writes = set()
        for part in ([s.cond, s.step] if isinstance(s, A.For) else [s.cond]):
            if isinstance(part, A.Expr):
                writes |= self.effects(part).writes
        if body_st < ESSENTIAL and not (writes & live):
            return live, DEAD
        live_in = head | step_reads
        if isinstance(s, A.For) and s.init is not None:
            init = s.init
            self.status[id(init)] = ESSENTIAL
            if isinstance(init, A.DeclStmt) and isinstance(init.decl, A.VariableDecl):
                for d in init.decl.declarators:
                    self.live_decl[id(d)] = True
                    live_in.discard((id(init.decl), d.name))
                    if d.init is not None:
                        live_in |= self.effects(d.init).reads
            elif isinstance(init, A.ExprStmt) and init.expr is not None:
                live_in |= self.effects(init.expr).reads
        return live_in, ESSENTIAL

    visit_While = visit_For

    def visit_DoWhile(self, s: A.DoWhile, live: set) -> tuple[set, int]:
        saved = self.control_reads
        self.control_reads = False
        try:
            _, st = self._do_while(s, live)
        finally:
            self.control_reads = saved
        if st == DEAD:
            return live, DEAD
        return self._do_while(s, live)

    def _do_while(self, s: A.DoWhile, live: set) -> tuple[set, int]:
        cond_reads = self.effects(s.cond).reads if self.control_reads else set()
        cond_in = set(live) | cond_reads
        ctx = _Loop(set(live), cond_in)
        self.loops.append(ctx)
        try:
            while True:
                ctx.cont = cond_in
                body_in, body_st = self.stmt(s.body, cond_in)
                new = set(live) | cond_reads | body_in
                if new == cond_in:
                    break
                cond_in = new
        finally:
            self.loops.pop()
        if body_st < ESSENTIAL and not (self.effects(s.cond).writes & live):
            return live, DEAD
        return body_in | cond_reads, ESSENTIAL

    def visit_Switch(self, s: A.Switch, live: set) -> tuple[set, int]:
        self.loops.append(_Loop(set(live), None))
        try:
            cur = set(live)
            entries: set = set()
            has_default = False
            status = DEAD
            for stmt in reversed(s.body.stmts):
                if isinstance(stmt, A.Case):
                    entries |= cur
                    has_default = has_default or stmt.expr is None
                    self.status[id(stmt)] = CONTROL
                    continue
                cur, st = self.stmt(stmt, cur)
                status = max(status, st)
        finally:
            self.loops.pop()
        eff = self.effects(s.expr)
        if status < ESSENTIAL and not (eff.writes & live) and not eff.essential:
            return live, DEAD
        if not has_default:
            entries |= live
        return entries | eff.reads, ESSENTIAL


class _Rebuild(NodeVisitor):
    """Visiting a kept statement drops what it holds that is dead."""

    def __init__(self, lv: _Liveness):
        self.lv = lv
        # (the list holding the statement or None, the DeclStmt, its original declarators)
        self.decls: list[tuple[Optional[list], A.DeclStmt, list[A.Declarator]]] = []

    def kept(self, s: A.Stmt) -> bool:
        return self.lv.status.get(id(s), DEAD) > DEAD

    def block(self, stmts: list) -> list:
        out = []
        for s in stmts:
            is_var_decl = (isinstance(s, A.DeclStmt) and isinstance(s.decl, A.VariableDecl)
                           and bool(s.decl.declarators))
            if isinstance(s, A.Case) or self.kept(s) or is_var_decl:
                # a declaration whose variables are all dead stays a candidate for restore()
                self.visit(s, out)
                if not (isinstance(s, A.Compound) and not s.stmts):
                    out.append(s)
        return out

    def sub(self, s: Optional[A.Stmt], optional: bool) -> Optional[A.Stmt]:
        if s is None:
            return None
        if not self.kept(s):
            return None if optional else A.Compound([], loc=s.loc)
        self.visit(s, None)
        return s

    def generic_visit(self, s: A.Stmt, container: Optional[list]) -> None:
        pass

    def visit_Compound(self, s: A.Compound, container: Optional[list]) -> None:
        s.stmts = self.block(s.stmts)

    def visit_If(self, s: A.If, container: Optional[list]) -> None:
        s.then = self.sub(s.then, optional=False)
        s.else_ = self.sub(s.else_, optional=True)

    def visit_For(self, s, container: Optional[list]) -> None:
        s.body = self.sub(s.body, optional=False)

    visit_While = visit_DoWhile = visit_For

    def visit_Switch(self, s: A.Switch, container: Optional[list]) -> None:
        s.body.stmts = self.block(s.body.stmts)

    def visit_DeclStmt(self, s: A.DeclStmt, container: Optional[list]) -> None:
        if isinstance(s.decl, A.VariableDecl) and s.decl.declarators:
            original = list(s.decl.declarators)
            s.decl.declarators = [d for d in original if self.lv.live_decl.get(id(d), False)]
            self.decls.append((container, s, original))

    def restore(self, main: A.FunctionDecl) -> None:
        """Put back the declarations of dead variables that are still referenced (without
        their initialiser, which nothing reads, unless the variable is ``const``); remove the
        declaration statements left empty."""
        restored: dict[int, A.Declarator] = {}
        changed = True
        while changed:
            changed = False
            refs = {var_key(n) for n in walk(main.body) if isinstance(n, A.Ident)}
            for _, s, original in self.decls:
                rebuilt = []
                for d in original:
                    if self.lv.live_decl.get(id(d), False):
                        rebuilt.append(d)
                    elif id(d) in restored:
                        rebuilt.append(restored[id(d)])
                    elif (id(s.decl), d.name) in refs:
                        const = "const" in s.decl.type.qualifiers
                        new = d if const else A.Declarator(d.name, d.array_dims, None, loc=d.loc)
                        restored[id(d)] = new
                        rebuilt.append(new)
                        changed = True
                s.decl.declarators = rebuilt
        for container, s, _ in self.decls:
            if container is not None and not s.decl.declarators:
                for i, x in enumerate(container):
                    if x is s:
                        del container[i]
                        break


def prune_main(unit: A.TranslationUnit) -> None:
    """Dead-code elimination inside ``main`` (see the module docstring). ``unit`` must have
    been type-checked (identifiers resolved)."""
    main = main_function(unit)
    if main is None:
        return
    lv = _Liveness(unit, main)
    lv.stmt(main.body, set(lv.observable))
    lv.status[id(main.body)] = ESSENTIAL
    rb = _Rebuild(lv)
    rb.visit(main.body, None)
    rb.restore(main)
    tidy_blocks(main.body)


def _header_names(s: A.Stmt) -> set[str]:
    """The names a loop's header declares (``for (int i = ...``, ``while (bool b = ...)``)."""
    decls = [s.init.decl] if isinstance(s, A.For) and isinstance(s.init, A.DeclStmt) else []
    cond = getattr(s, "cond", None)
    if isinstance(cond, A.VariableDecl):
        decls.append(cond)
    return {d.name for v in decls if isinstance(v, A.VariableDecl) for d in v.declarators}


class _Tidy(NodeVisitor):
    """In place: the empty blocks dropped and single nested blocks flattened (:func:`tidy_blocks`)."""

    def generic_visit(self, s, keep_names: frozenset = frozenset()) -> None:
        pass

    def visit_Compound(self, s: A.Compound, keep_names: frozenset = frozenset()) -> None:
        out = []
        for x in s.stmts:
            self.visit(x)
            if not (isinstance(x, A.Compound) and not x.stmts):
                out.append(x)
        while len(out) == 1 and isinstance(out[0], A.Compound) and not (
                keep_names and keep_names & {d.name for x in out[0].stmts if isinstance(x, A.DeclStmt)
                                             and isinstance(x.decl, A.VariableDecl)
                                             for d in x.decl.declarators}):
            out = out[0].stmts
        s.stmts = out

    def visit_If(self, s: A.If, keep_names: frozenset = frozenset()) -> None:
        self.visit(s.then)
        if s.else_ is not None:
            self.visit(s.else_)

    def visit_For(self, s, keep_names: frozenset = frozenset()) -> None:
        self.visit(s.body, frozenset(_header_names(s)))

    visit_While = visit_DoWhile = visit_For

    def visit_Switch(self, s: A.Switch, keep_names: frozenset = frozenset()) -> None:
        for x in s.body.stmts:
            self.visit(x)
        # labels left with no statement after them (their code was pruned) end the body: a
        # label must precede a statement, and nothing would run there anyway
        while s.body.stmts and isinstance(s.body.stmts[-1], A.Case):
            s.body.stmts.pop()


def tidy_blocks(s: Optional[A.Stmt], keep_names: frozenset = frozenset()) -> None:
    """In place: drop the empty blocks ``{ }`` inside statement lists, and let a block whose
    only statement is a block hold that block's statements instead (``{ { x; } }`` becomes
    ``{ x; }``), unless the inner block declares a name in ``keep_names`` (a loop body shares
    its scope with the loop header's declarations, so ``for (int i...) { { int i; } }`` must
    keep its inner block).

    >>> from rrcache.glsl.parser import parse_source
    >>> from rrcache.glsl.printer import print_glsl
    >>> unit = parse_source("void main() { { { { x = 1.0; } { } } } if (c) { { { } } y = 2.0; } }")
    >>> tidy_blocks(unit.decls[0].body)
    >>> print(print_glsl(unit), end="")
    void main()
    {
        {
            x = 1.0;
        }
        if (c)
        {
            y = 2.0;
        }
    }
    """
    if s is not None:
        _Tidy().visit(s, keep_names)


class _Names(NodeVisitor):
    """Names a declaration references: identifiers, called functions and constructors, type
    names (struct types)."""

    def __init__(self):
        self.found: set[str] = set()

    def visit_Ident(self, n) -> None:
        self.found.add(n.name)

    def visit_Call(self, n) -> None:
        self.found.add(n.name)
        self.generic_visit(n)

    def visit_TypeSpecifier(self, n) -> None:
        if n.name:
            self.found.add(n.name)
        self.generic_visit(n)


def _names(node: A.Node) -> set[str]:
    v = _Names()
    v.visit(node)
    return v.found


def prune_globals(unit: A.TranslationUnit, keep: Iterable[A.Node] = ()) -> None:
    """Remove the global declarations nothing needed references (see the module docstring).
    ``keep`` lists declarations that stay whatever happens (and count as references)."""
    keep_ids = {id(d) for d in keep}
    refs: set[str] = set()
    walked: set[int] = set()

    def visit(node: A.Node) -> None:
        if id(node) not in walked:
            walked.add(id(node))
            refs.update(_names(node))

    changed = True
    while changed:
        size = (len(walked), len(refs))
        for d in unit.decls:
            forced = id(d) in keep_ids or (isinstance(d, A.FunctionDecl) and d.name == "main")
            if isinstance(d, A.VariableDecl):
                for x in d.declarators:
                    if forced or x.name in refs:
                        visit(x)
                        visit(d.type)
                if forced or _needed(d, refs):
                    visit(d.type)
            elif forced or _needed(d, refs):
                visit(d)
        changed = (len(walked), len(refs)) != size
    out = []
    declared: set[str] = set()
    for d in unit.decls:
        if id(d) in keep_ids:
            out.append(d)
            continue
        if not _needed(d, refs) and not (isinstance(d, A.FunctionDecl) and d.name == "main"):
            continue
        if isinstance(d, A.VariableDecl) and d.declarators:
            kept = [x for x in d.declarators if x.name in refs]
            if not kept:
                d = A.VariableDecl(d.type, [], loc=d.loc)  # only its struct type is needed
            elif len(kept) != len(d.declarators):
                d = A.VariableDecl(d.type, kept, loc=d.loc)
            declared.update(x.name for x in d.declarators)
        out.append(d)
    unit.decls = [d for d in out if not (isinstance(d, A.QualifierDecl) and d.names
                                         and not all(n in declared or n.startswith("gl_")
                                                     for n in d.names))]


class _Needed(NodeVisitor):
    """Whether a global declaration is referenced by a name in ``refs``."""

    def visit_FunctionDecl(self, d: A.FunctionDecl, refs: set) -> bool:
        return d.name in refs

    def visit_VariableDecl(self, d: A.VariableDecl, refs: set) -> bool:
        if any(x.name in refs for x in d.declarators):
            return True
        st = d.type.spec.struct
        return st is not None and st.name is not None and st.name in refs

    def visit_InterfaceBlock(self, d: A.InterfaceBlock, refs: set) -> bool:
        if d.instance_name:
            return d.instance_name in refs
        return any(x.name in refs for m in d.members for x in m.declarators)

    def generic_visit(self, d, refs: set) -> bool:
        return True  # precision and qualifier declarations (checked against what remains)


_needed = _Needed().visit


def prune(unit: A.TranslationUnit, keep: Iterable[A.Node] = ()) -> A.TranslationUnit:
    """Dead-code elimination of ``main`` followed by the removal of unused globals; in place.
    Returns ``unit``."""
    keep = list(keep)
    prune_main(unit)
    prune_globals(unit, keep)
    return unit

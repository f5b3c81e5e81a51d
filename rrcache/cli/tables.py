"""Tables for the commands' output that read well anywhere: never cut.

On a terminal a table is drawn by rich, its long text columns wrapped (folded) at the
terminal's width, never ended with an ellipsis. Anywhere else (a pipe, a file, CI, a notebook)
it is plain text: columns padded to their widest cell, every cell whole, lines as long as they
need to be, so ``grep`` and ``less -S`` see every value (``--json`` gives the data itself).

>>> import io
>>> from rich.console import Console
>>> t = TextTable("selections", [("level", "left"), ("node", "left"), ("Δn", "right")])
>>> t.add_row("e1 ≥ 45 dB", "n74: sin(p.x * 7.0 + 5.0 * turbulence(p)) * 0.5 + 0.5", "12")
>>> out = io.StringIO()
>>> t.print(Console(file=out, force_terminal=False, width=40))
>>> print(out.getvalue().rstrip())
selections
level       node                                                   Δn
----------  -----------------------------------------------------  --
e1 ≥ 45 dB  n74: sin(p.x * 7.0 + 5.0 * turbulence(p)) * 0.5 + 0.5  12
"""
from __future__ import annotations

from typing import Optional, Sequence

from rich.console import Console
from rich.table import Table


class TextTable:
    """A table of text cells: ``columns`` are ``(name, justify)`` pairs (``left`` or ``right``)."""

    def __init__(self, title: Optional[str], columns: Sequence[tuple[str, str]]):
        self.title = title
        self.columns = [(str(name), justify) for name, justify in columns]
        self.rows: list[list[str]] = []

    def add_row(self, *cells) -> None:
        if len(cells) != len(self.columns):
            raise ValueError(f"{len(cells)} cells for {len(self.columns)} columns")
        self.rows.append(["" if c is None else str(c) for c in cells])

    def plain(self) -> str:
        """The table as plain text (title, header, rule, rows), every cell whole."""
        names = [name for name, _ in self.columns]
        widths = [max([len(name)] + [len(r[i]) for r in self.rows]) for i, name in enumerate(names)]

        def line(cells):
            out = []
            for (_, justify), width, cell in zip(self.columns, widths, cells):
                out.append(cell.rjust(width) if justify == "right" else cell.ljust(width))
            return "  ".join(out).rstrip()

        lines = [self.title] if self.title else []
        lines += [line(names), line(["-" * w for w in widths])]
        lines += [line(r) for r in self.rows]
        return "\n".join(lines)

    def rich(self) -> Table:
        """The table for a terminal: rich, long cells folded onto more lines, never cut."""
        table = Table(title=self.title)
        for name, justify in self.columns:
            table.add_column(name, justify=justify, overflow="fold")
        for row in self.rows:
            table.add_row(*row)
        return table

    def __rich__(self) -> Table:
        """``console.print(table)`` draws it with rich (:meth:`print` chooses by the console)."""
        return self.rich()

    def print(self, console: Console) -> None:
        """Draw it on ``console``: rich on a terminal, plain text elsewhere."""
        if console.is_terminal:
            console.print(self.rich())
        else:
            console.print(self.plain(), highlight=False, markup=False, emoji=False, soft_wrap=True)

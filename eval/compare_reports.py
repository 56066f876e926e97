"""Before -> after tables from two benchmark reports (`suctionbench report` report.md files).

Every table of the new report whose header row also appears in the old one is printed again with
each numeric cell that differs written "old -> new" (rows matched on their non-numeric leading
cells: policy / metric, set, trials). Used for eval/README.md's before -> after sections.

Usage: python eval/compare_reports.py OLD/report.md NEW/report.md [--columns 'success %,AP %']
       git show REV:eval/benchmark/report.md > /tmp/old.md  # the committed snapshot as "before"
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

NUMBER = re.compile(r"^-?\d+(\.\d+)?$")


def tables(text: str) -> list[list[list[str]]]:
    """Markdown pipe tables in `text`: a list of tables, each a list of rows of cells (header
    first, the separator row dropped)."""
    out, current = [], []
    for line in text.splitlines():
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not all(set(c) <= {"-", ":"} for c in cells):
                current.append(cells)
        elif current:
            out.append(current)
            current = []
    if current:
        out.append(current)
    return out


def key_of(row: list[str], width: int) -> tuple[str, ...]:
    """The identifying cells of a row: its first `width` cells."""
    return tuple(row[:width])


def compare(old: list[list[str]], new: list[list[str]], columns: list[str] | None) -> list[list[str]]:
    header = new[0]
    keep = [i for i, name in enumerate(header) if columns is None or i < 3 or name in columns]
    width = 3 if len(header) > 3 else 1
    before = {key_of(r, width): r for r in old[1:]}
    rows = [[header[i] if i < width else f"{header[i]} before -> after" for i in keep]]
    for row in new[1:]:
        previous = before.get(key_of(row, width))
        cells = []
        for i in keep:
            value = row[i]
            if i >= width and previous is not None and i < len(previous) and (NUMBER.match(value) or value == "-"):
                value = f"{previous[i]} -> {value}"
            cells.append(value)
        rows.append(cells)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--columns", default=None, help="comma-separated header names to keep (besides the keys)")
    args = parser.parse_args()
    columns = None if args.columns is None else [c.strip() for c in args.columns.split(",")]
    old_tables = {tuple(t[0]): t for t in tables(args.old.read_text())}
    for table in tables(args.new.read_text()):
        old = old_tables.get(tuple(table[0]))
        if old is None:
            continue
        rows = compare(old, table, columns)
        print("| " + " | ".join(rows[0]) + " |")
        print("|" + "---|" * len(rows[0]))
        for row in rows[1:]:
            print("| " + " | ".join(row) + " |")
        print()


if __name__ == "__main__":
    main()

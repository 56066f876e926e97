"""The `suctionbench` command line: parse, call the library, print (rich) or --json.

One module per command group; `common` holds the app, the contract runner (exit codes, JSON on
the last stdout line) and the shared tables and progress bars. Importing the command modules
registers their commands, in the order `--help` lists them.
"""

from __future__ import annotations

from importlib import import_module

from suctionbench.cli.common import app

COMMAND_MODULES = ("about", "label", "pick", "data", "evaluate", "plan", "bench", "objects", "train")
"""Command modules, imported (so registered) in this order: the order of `suctionbench --help`."""

for _name in COMMAND_MODULES:
    import_module(f"suctionbench.cli.{_name}")

__all__ = ["app", "main"]


def main() -> None:
    """Console-script entry point."""
    from suctionbench.allocator import keep_large_blocks

    keep_large_blocks()  # planning's large temporaries reused, not faulted in anew (allocator module)
    app()

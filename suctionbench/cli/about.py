"""`suctionbench version`."""

from __future__ import annotations

from suctionbench import __version__
from suctionbench.cli.common import JsonOpt, app, run_command


@app.command()
def version(as_json: JsonOpt = False) -> None:
    """Print the suctionbench version."""
    run_command(as_json, lambda: {"version": __version__})
    if not as_json:
        print(__version__)

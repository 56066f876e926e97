"""Shared parts of the `suctionbench` command line: the app and its groups, the contract runner, progress, tables.

Contract (DESIGN.md): with --json, the last stdout line is exactly one JSON object and human
output goes to stderr; exit 0 on success, 2 on bad input (one line naming the input and the
problem), 1 on an internal failure. Long work shows a progress bar on a terminal only.
"""

from __future__ import annotations

import json
import os
import sys
import traceback
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, get_args

import numpy as np
import typer
from rich import box
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TextColumn, TimeRemainingColumn
from rich.table import Table
from rich.text import Text
from typer.core import _click

from suctionbench.errors import InputError
from suctionbench.io import WRITE_ERRNOS, json_safe
from suctionbench.validate import OPTION_RULES, SIZE_OPTIONS, Rule, os_error_message

FINITE = Rule()
"""A float option without a rule of its own is still finite."""


def numeric_type(param: Any) -> type | None:
    """int or float when `param` takes one number (optional or not), else None."""
    annotation = getattr(getattr(param, "type_descriptor", None), "annotation", None)
    kinds = {a for a in (get_args(annotation) or (annotation,)) if a is not type(None)}
    return kinds.pop() if len(kinds) == 1 and kinds <= {int, float} else None


def check_numeric_options(command: Any) -> None:
    """Give every int / float option of `command` and its subcommands its rule from `OPTION_RULES`,
    checked as the option is parsed (a usage error: exit 2, one line)."""
    for param in command.params:
        kind = numeric_type(param)
        if kind is None:
            continue
        rule = OPTION_RULES.get(param.name or "", FINITE if kind is float else None)
        if rule is not None:
            param.callback = _rule_callback(rule, param.callback)
    for sub in getattr(command, "commands", {}).values():
        check_numeric_options(sub)


def _rule_callback(rule: Rule, then: Callable[..., Any] | None) -> Callable[..., Any]:
    def callback(ctx: Any, param: Any, value: Any) -> Any:
        what = param.opts[0] if param.opts else param.name
        try:
            value = rule.check(value, what)
        except InputError as exc:
            raise _click.exceptions.UsageError(str(exc), ctx) from None
        return then(ctx, param, value) if then is not None else value

    return callback


class ContractGroup(typer.core.TyperGroup):
    """Top-level command group that keeps the CLI contract for usage errors too.

    Click reports a bad option before any command runs; here such errors still exit 2 with one
    stderr line and, under --json, still end stdout with a JSON object. Every numeric option is
    checked against its rule (`suctionbench.validate.OPTION_RULES`) while it is parsed.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        check_numeric_options(self)

    def main(self, args: Any = None, *pargs: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        argv = list(sys.argv[1:] if args is None else args)
        try:
            rv = super().main(argv, *pargs, standalone_mode=False, **kwargs)
        except _click.exceptions.NoArgsIsHelpError as exc:  # a bare group: its help, as before
            exc.show()
            rv = exc.exit_code
        except _click.exceptions.ClickException as exc:
            error_line(exc.format_message())
            emit({"ok": False, "error": exc.format_message()}, "--json" in argv)
            rv = exc.exit_code
        except typer.Abort:  # end of input at a prompt, or a closed pipe under --help
            err.print("aborted")
            rv = 1
        code = rv if isinstance(rv, int) else 0
        if not standalone_mode:
            return code
        sys.exit(code)


app = typer.Typer(
    cls=ContractGroup,
    add_completion=False,
    no_args_is_help=True,
    help="Robust suction grasp labels, datasets, GQ-CNN policies and a MuJoCo benchmark.",
)
bench_app = typer.Typer(no_args_is_help=True, help="Speed figures, each timed against its reference in one run.")
app.add_typer(bench_app, name="bench")
objects_app = typer.Typer(no_args_is_help=True, help="Object sets: list, show, build, import, generate the corpus.")
app.add_typer(objects_app, name="objects")
dataset_app = typer.Typer(no_args_is_help=True, help="Inspect generated datasets.")
app.add_typer(dataset_app, name="dataset")
model_app = typer.Typer(no_args_is_help=True, help="Inspect trained GQ-CNN models.")
app.add_typer(model_app, name="model")

err = Console(stderr=True, soft_wrap=True, markup=False)  # soft wrap: one error, one line
"""Human output on stderr. No rich markup, here or in `console()`: what the commands print holds the
user's strings (object names, paths, policy names), and '[red]' or '[/]' in them prints literally."""


def console() -> Console:
    """The console for human output on stdout (tables, summaries): markup off, like `err`."""
    return Console(markup=False)


JsonOpt = Annotated[bool, typer.Option("--json", help="Print one JSON object on the last stdout line.")]
SeedOpt = Annotated[int, typer.Option("--seed", help="Seed of every random draw.")]
UnitsOpt = Annotated[str, typer.Option(help="Units of the mesh file: m, cm, mm, in, or auto (an STL in metres or "
                                            "millimetres, whichever size is plausible; other formats in metres).")]

def emit(result: dict[str, Any], as_json: bool) -> None:
    """Under --json, print `result` as one strict JSON line (NaN and infinities become null)."""
    if as_json:
        print(json.dumps(json_safe(result), sort_keys=False, allow_nan=False))


def error_line(message: str, kind: str = "error") -> None:
    """One stderr line 'error: MESSAGE', the message printed as plain text (never read as markup)."""
    err.print(Text.assemble((f"{kind}:", "bold red"), " ", " ".join(str(message).split())), highlight=False)


def note(message: str) -> None:
    """One stderr line 'note: MESSAGE' (plain text): something the user should know that is no error."""
    err.print(Text.assemble(("note:", "bold cyan"), " ", " ".join(str(message).split())), highlight=False)


def run_command(as_json: bool, body: Callable[[], dict[str, Any]], *, output: str | None = None) -> None:
    """Run a command body under the CLI contract (exit codes, JSON on the last line).

    Bad input (`InputError`), and a file system that refuses a write or a read (disk full, no
    permission, read-only, a file where a directory must be: an `OSError`), exit 2 with one line
    naming the path: the error's own, else `output` (what the command writes, e.g. "--out 'runs/a'"),
    for a write error that carries none. Memory exhausted despite the size checks (MemoryError, or a
    tensor allocation that fails) exits 2 naming the command's size options. Anything else is an
    internal failure: exit 1 with the traceback on stderr.

    Python warnings raised while the body runs (numerical warnings of a library, say) are held
    back: a refused input prints its one error line only; a success prints them after its work,
    one line each.
    """
    with warnings.catch_warnings(record=True) as caught:
        try:
            result = body()
        except typer.Exit:
            raise
        except InputError as exc:
            fail_input(str(exc), as_json)
        except OSError as exc:
            if exc.filename is None and exc.errno not in WRITE_ERRNOS:  # not about a file or a full disk: a bug
                _print_warnings(caught)
                fail_internal(exc, as_json)
            message = os_error_message(exc)
            fail_input(f"{output}: {message}" if output and exc.filename is None else message, as_json)
        except MemoryError:
            fail_input(_out_of_memory(), as_json)
        except KeyboardInterrupt:  # Ctrl-C: one line (and the JSON line), exit 130 as shells expect
            error_line("interrupted (Ctrl-C)")
            emit({"ok": False, "error": "interrupted"}, as_json)
            raise typer.Exit(130) from None
        except Exception as exc:  # an internal failure: say so, with the traceback on stderr
            if _is_allocation_failure(exc):
                fail_input(_out_of_memory(), as_json)
            _print_warnings(caught)
            fail_internal(exc, as_json)
    _print_warnings(caught)
    emit({"ok": True, **result}, as_json)


def _print_warnings(caught: list[warnings.WarningMessage]) -> None:
    seen = set()
    for w in caught:
        line = f"{w.category.__name__}: {' '.join(str(w.message).split())} ({Path(w.filename).name}:{w.lineno})"
        if line not in seen:
            seen.add(line)
            err.print(Text.assemble(("warning:", "yellow"), " ", line), highlight=False)


def _is_allocation_failure(exc: BaseException) -> bool:
    """A tensor library's failed allocation (torch raises RuntimeError, not MemoryError)."""
    text = str(exc).lower()
    return isinstance(exc, RuntimeError) and ("can't allocate memory" in text or "out of memory" in text)


def _out_of_memory() -> str:
    """The out-of-memory message, naming the size options of the running command and their values."""
    from typer._click.globals import get_current_context

    ctx = get_current_context(silent=True)
    sizes = []
    if ctx is not None:
        for param in ctx.command.params:
            value = ctx.params.get(param.name or "")
            if param.name in SIZE_OPTIONS and value is not None and param.opts:
                sizes.append(f"{param.opts[0]} {value}")
    return f"out of memory with {' '.join(sizes)} (use smaller sizes)" if sizes else "out of memory (use smaller sizes)"


def fail_input(message: str, as_json: bool) -> None:
    """Exit 2 for bad input: one stderr line, and the JSON error line under --json."""
    error_line(message)
    emit({"ok": False, "error": message}, as_json)
    raise typer.Exit(2) from None


def fail_internal(exc: BaseException, as_json: bool) -> None:
    """Exit 1 for an internal failure, with its traceback on stderr."""
    error_line(f"{type(exc).__name__}: {exc}", "internal error")
    traceback.print_exception(exc, file=sys.stderr)
    emit({"ok": False, "error": f"internal: {type(exc).__name__}: {exc}"}, as_json)
    raise typer.Exit(1) from None


class RateColumn(ProgressColumn):
    """Items per second of a progress task."""

    def render(self, task: Any) -> Text:
        return Text(f"{task.speed:,.0f}/s" if task.speed else "-/s")


@contextmanager
def progress_bar(total: int, label: str, enabled: bool) -> Iterator[Callable[[int], None]]:
    """A rich progress bar on an interactive stderr; a no-op callback otherwise."""
    if not enabled or not err.is_terminal:
        yield lambda _n: None
        return
    columns = (TextColumn(label), BarColumn(), MofNCompleteColumn(), RateColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task(label, total=total)
        yield lambda n: bar.advance(task, n)


def parse_vector(text: str, size: int, what: str) -> np.ndarray:
    """Parse 'a,b,c' into a finite float vector of `size`, or raise InputError naming `what`."""
    try:
        values = np.array([float(x) for x in text.split(",")], dtype=float)
    except ValueError:
        raise InputError(f"{what} '{text}': expected {size} comma-separated numbers") from None
    if values.shape != (size,):
        raise InputError(f"{what} '{text}': expected {size} comma-separated numbers, got {len(values)}")
    if not np.all(np.isfinite(values)):
        raise InputError(f"{what} '{text}': values must be finite")
    return values


def resolve_workers(requested: int) -> int:
    """--workers: 0 means every core."""
    return requested or os.cpu_count() or 1


def print_kv(title: str, result: dict[str, Any]) -> None:
    """A two-column table of a command's result (human output)."""
    table = Table(title=title, show_header=False)
    for key, value in result.items():
        table.add_row(key, f"{value:.4g}" if isinstance(value, float) else str(value))
    console().print(table)


def record_row(record: Any) -> dict[str, Any]:
    return {
        "key": record.key,
        "generator": record.generator,
        "faces": record.faces,
        "parts": len(record.parts),
        "mass": record.mass,
        "extents": record.extents,
        "stable_poses": len(record.stable_poses),
    }


def print_rows(title: str, rows: list[dict[str, Any]]) -> None:
    if not rows:
        err.print(f"{title}: none")
        return
    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False)  # no vertical rules: 80 columns hold more
    for col in rows[0]:
        table.add_column(col)
    for row in rows:
        table.add_row(*[
            f"{v:.4g}" if isinstance(v, float) else ",".join(f"{x:.3g}" for x in v) if isinstance(v, list) else str(v)
            for v in row.values()
        ])
    console().print(table)

"""Command-line entry point `impact`: try a case without Snakemake.

Each sub-command prints one JSON object on stdout (`impact design` prints text unless
--json).  Flags are named after the
model's symbols (model.md); a value out of range is refused with a message
naming the flag and exit status 2.

The parser (:mod:`.flags`) loads the model alone; each sub-command is a function of its own module
(:data:`COMMANDS`), which loads what the command runs, so that ``impact --help`` and a refused flag answer at once.
"""

from __future__ import annotations

import importlib
import json
import math
import os
import sys

from impact.cli.flags import build_parser
from impact.model.params import ParameterError
from impact.model.records import RecordError

#: each sub-command's function, as module:function, imported when that command runs
COMMANDS = {
    "run": "impact.cli.paper:run",
    "sweep": "impact.cli.paper:run_sweep",
    "masri": "impact.cli.paper:masri",
    "quake": "impact.cli.buildings:quake",
    "pushover": "impact.cli.buildings:pushover",
    "records": "impact.cli.buildings:records",
    "design": "impact.cli.design:design",
    "compile": "impact.cli.upkeep:compile_kernels",
    "verify-archive": "impact.cli.upkeep:verify_archive",
}

__all__ = ["COMMANDS", "build_parser", "main"]


def command(name: str):
    """The function that runs sub-command `name`."""
    module, function = COMMANDS[name].split(":")
    return getattr(importlib.import_module(module), function)


def _finite(obj):
    """JSON without NaN/inf tokens: they become null."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def main(argv=None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if getattr(args, "average_from", 0.0) >= getattr(args, "periods", math.inf):
        ap.error(f"argument --average-from: {args.average_from} must be below --periods = {args.periods}")
    try:
        out = command(args.command)(args)
    except (ParameterError, RecordError) as exc:
        ap.error(str(exc))
    try:
        if isinstance(out, str):  # a command's text for a person (impact design without --json)
            sys.stdout.write(out + "\n")
        else:
            json.dump(_finite(out), sys.stdout, indent=1)
            sys.stdout.write("\n")
        sys.stdout.flush()
    except BrokenPipeError:
        # the reader stopped early (impact ... | head): not an error, and no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


"""The ``impact`` command (and ``python -m impact``): the study's kernel sets chosen before numpy loads, then the CLI.

The command line computes with the study's kernel sets (:mod:`impact.kernels`), which OpenBLAS and numpy read
once, when they load; ``impact.cli`` loads numpy as it is imported, so it is imported only after they are chosen.
"""

from __future__ import annotations

from impact import kernels


def main(argv=None) -> int:
    kernels.apply()
    from impact.cli import main as run_command_line

    return run_command_line(argv)


if __name__ == "__main__":
    raise SystemExit(main())

"""The ``trajdrift`` command of the Python package: the command line of the Rust library, run in this
process (one compiled module for the command and the API)."""

from __future__ import annotations

import signal
import sys


def main() -> None:
    """Runs ``trajdrift`` with this process's arguments and exits with its exit code (0 ok, 1 failure,
    2 usage, 3 finished with a warning)."""
    from . import _trajdrift

    # Ctrl-C ends the command as it ends the binary (the interpreter's handler would wait for the
    # Rust code to return).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.stdout.flush()
    sys.stderr.flush()
    sys.exit(_trajdrift.main(["trajdrift", *sys.argv[1:]]))


if __name__ == "__main__":
    main()

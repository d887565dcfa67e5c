"""``python -m trajdrift``: the command line, as the ``trajdrift`` command."""

from ._cli import main

main()

"""`python -m camopt` runs the command-line interface."""

from camopt.cli import main

main()

"""The ``cosleec`` command line.

One module per sub-command, each with ``add_parser`` (its options) and ``run`` (which
returns the exit code); :mod:`cosleec.cli.main` assembles them and is the only place that
turns errors into messages and exit codes.
"""

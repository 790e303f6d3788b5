"""The ``cosleec`` command line."""

"""Subcommands of the ``fuzzrisk`` command line (see :mod:`monitor.cli`)."""

"""One module per ``smd-statespace`` subcommand; :mod:`smd_statespace.cli` dispatches."""

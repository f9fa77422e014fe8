"""The ``beadrod`` subcommands, one module each: its flags (``register``) and its run.

Each is a thin layer over :mod:`beadrod.workflows.api` and the pipeline; the list of
commands is :data:`beadrod.workflows.cli.COMMAND_MODULES`.
"""

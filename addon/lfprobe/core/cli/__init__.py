"""The lfprobe command line (bpy-free): ``./lfprobe SUBCOMMAND ...`` runs
``python -m lfprobe.core.cli``. main.py builds the parser and runs a subcommand; arguments.py
holds the options several subcommands share; each other module adds its subcommands."""

from .main import build_parser, main  # noqa: F401  (lfprobe.core.cli.main, .build_parser)

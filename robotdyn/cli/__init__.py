"""robotdyn.cli.commands: see robotdyn/cli/__init__.py (placeholder written by relayout.py)."""

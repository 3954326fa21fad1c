"""robotdyn.sweep.runner: see robotdyn/sweep/__init__.py (placeholder written by relayout.py)."""

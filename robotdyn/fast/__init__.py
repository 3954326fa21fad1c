"""robotdyn.fast: see robotdyn/fast/__init__.py (placeholder written by relayout.py)."""

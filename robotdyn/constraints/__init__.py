"""robotdyn.constraints: see robotdyn/constraints/__init__.py (placeholder written by relayout.py)."""

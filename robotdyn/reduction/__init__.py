"""robotdyn.reduction: see robotdyn/reduction/__init__.py (placeholder written by relayout.py)."""

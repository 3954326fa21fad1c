"""robotdyn.interfaces: see robotdyn/interfaces/__init__.py (placeholder written by relayout.py)."""

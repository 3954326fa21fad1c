"""robotdyn.description.urdf: see robotdyn/description/__init__.py (placeholder written by relayout.py)."""

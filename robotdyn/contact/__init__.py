"""robotdyn.contact: see robotdyn/contact/__init__.py (placeholder written by relayout.py)."""

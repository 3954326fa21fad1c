"""robotdyn.simulation.engine: see robotdyn/simulation/__init__.py (placeholder written by relayout.py)."""

"""Shared fixtures: robots are built once per session (building expands xacro and parses URDF)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tests/oracles importable as `oracles`

import robotdyn  # noqa: E402


@pytest.fixture(scope="session")
def quasimoro():
    return robotdyn.load("quasimoro")


@pytest.fixture(scope="session")
def quasimoro_com():
    return robotdyn.load("quasimoro", {"inertia_about": "com"})

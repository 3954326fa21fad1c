"""Traction along simulations (robotdyn.contact.traction): loads and required friction of a disc rolling down an incline
against the closed form, event times, the CSV columns and the summary line of ``robotdyn simulate``."""

from __future__ import annotations

import numpy as np
import pytest

from robotdyn.cli.commands import main
from robotdyn.errors import InputError
from robotdyn.simulation.engine import simulate
from robotdyn.contact.traction import Traction, _events, traction

from test_contact_forces import _disc_on_ramp


@pytest.fixture(scope="module")
def rolling_disc():
    robot, q0 = _disc_on_ramp(0.4)
    traj = simulate(robot, 0.5, q0, np.zeros(robot.mobility), n_out=51, progress=False)
    return robot, traj


def test_disc_on_incline_loads_and_required_mu(rolling_disc):
    """Rolling down an incline: f_n = m g cos(alpha) and mu_req = tan(alpha) k/(1+k) at every sample, while the
    disc accelerates (closed form, k = I/(m R^2))."""
    robot, traj = rolling_disc
    m, k, g, alpha = 2.0, 0.04 / (2.0 * 0.09), 9.81, np.arctan(0.4)
    tr = traction(robot, traj)
    assert tr.wheels == ["disc"] and tr.friction_determined.all()
    np.testing.assert_allclose(tr.normal[:, 0], m * g * np.cos(alpha), rtol=1e-9)
    np.testing.assert_allclose(tr.required_mu[:, 0], np.tan(alpha) * k / (1 + k), rtol=1e-9)
    assert np.ptp(traj.column("x")) > 0.1  # it did roll
    assert tr.events == []
    assert "no-slip assumption holds" in tr.summary()


def test_slip_event_when_mu_is_too_small(rolling_disc):
    robot, traj = rolling_disc
    need = np.tan(np.arctan(0.4)) * (2 / 9) / (1 + 2 / 9)
    assert traction(robot, traj, mu=1.01 * need).events == []
    events = traction(robot, traj, mu=0.99 * need).events
    assert [(e.kind, e.wheel, e.t) for e in events] == [("slip", "disc", 0.0)]
    assert events[0].value == pytest.approx(need, rel=1e-9)
    with pytest.raises(InputError, match="mu"):
        traction(robot, traj, mu=-0.1)
    with pytest.raises(InputError, match="unknown wheel"):
        traction(robot, traj, mu={"nope": 0.5})


def test_event_times_are_interpolated():
    """A load falling linearly through zero between samples: the lift-off time is where the line crosses."""
    t = np.linspace(0.0, 1.0, 11)
    fn = 10.0 - 13.0 * t  # crosses 0 at t = 10/13
    ft = 0.5 * np.ones_like(t)
    with np.errstate(divide="ignore"):
        mu_req = np.where(fn > 0, ft / fn, np.inf)
    tr = Traction(t, ["w"], fn[:, None], ft[:, None], mu_req[:, None], np.array([0.25]), np.array([True]))
    events = {e.kind: e for e in _events(tr)}
    assert events["lift-off"].t == pytest.approx(10 / 13, rel=1e-12)
    # required mu 0.5 / (10 - 13 t) reaches 0.25 at t = 8/13; the interpolation lies between the samples around it
    assert 0.6 <= events["slip"].t <= 8 / 13 + 1e-12


def test_cli_simulate_reports_traction(tmp_path, capsys):
    csv = tmp_path / "run.csv"
    png = tmp_path / "traction.png"
    rc = main(["simulate", "linkage_suspension", "--scenario", "straight_line", "--t-end", "0.5", "--quiet",
               "--mu", "0.5", "--csv", str(csv), "--traction-plot", str(png)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "traction: loads" in out and "friction of wheel2, wheel5 not determined" in out
    header = csv.read_text().splitlines()[0].split(",")
    assert "wheel1.normal" in header and "wheel1.mu_required" in header
    assert "wheel2.normal" in header and "wheel2.mu_required" not in header
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert np.all(data[:, header.index("wheel1.normal")] > 0)
    assert png.stat().st_size > 10_000


def test_cli_dump_forces(capsys):
    """dump --forces: the table and JSON; the planar Quasimoro's normal loads come from its floating twin, the split
    of its lateral force between the two wheels of one rigid axle is undetermined."""
    q = ["0", "0", "0", "0", "0", "0.3"]
    assert main(["dump", "quasimoro", "--q", *q, "--v", "1", "0.5", "0.2", "--tau", "0.1", "0.1", "--forces"]) == 0
    out = capsys.readouterr().out
    assert "contact forces (ground on wheel, contact frame)" in out and "undetermined" in out
    assert "note: normal loads from the out-of-plane equilibrium" in out
    assert main(["dump", "quasimoro", "--q", *q, "--v", "1", "0.5", "0.2", "--tau", "0", "0.2", "--forces",
                 "--json"]) == 0
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["forces"]["wheels"]["wheel_A"]["determined"]["normal"] is True
    assert data["forces"]["wheels"]["wheel_A"]["determined"]["lateral"] is False
    assert data["forces"]["wheels"]["wheel_A"]["required_mu"] is None
    assert main(["dump", "quasimoro", "--q", *q, "--v", "1", "0.5", "0.2", "--forces"]) == 2
    assert "--forces needs --tau" in capsys.readouterr().err


def test_cli_loads_use_the_torques_the_scenario_applied(tmp_path):
    """A scenario that builds its own torque law (omni caster's feed-forward path torques): the CSV's wheel loads
    and required friction are those of the torques simulated, not of an unactuated robot (which differ here)."""
    from robotdyn.robots import module
    import robotdyn

    csv = tmp_path / "circle.csv"
    assert main(["simulate", "omni_caster", "--scenario", "circle", "--t-end", "0.5", "--quiet", "--csv",
                 str(csv)]) == 0
    header = csv.read_text().splitlines()[0].split(",")
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    robot = robotdyn.load("omni_caster")
    sc = module("omni_caster").SCENARIOS["circle"]
    traj = sc.run(robot, t_end=0.5, progress=False)
    applied = traction(robot, traj, sc.torque_law(robot), method="reference")
    idle = traction(robot, traj, None, method="reference")
    for name, col in applied.columns().items():
        got = data[:, header.index(name)]
        assert np.allclose(got, col, rtol=1e-9, atol=1e-9), name
    for c in applied.columns():  # the friction the path needs comes from its torques: unactuated, it is ~0
        if "mu" in c:
            assert np.max(np.abs(applied.columns()[c] - idle.columns()[c])) > 0.5 * np.max(applied.columns()[c]), c


def test_cli_json_gives_required_mu_only_where_determined(capsys):
    """simulate --json: max_required_mu names only the wheels whose friction force rigid-body dynamics determine
    (wheel2 and wheel5 share theirs with their axle partners: their own value would be an arbitrary split's, and
    the text says "not determined"), as the streamed run already did."""
    import json

    rc = main(["simulate", "linkage_suspension", "--scenario", "straight_line", "--t-end", "0.2", "--quiet",
               "--json"])
    data = json.loads(capsys.readouterr().out)
    assert rc == 0
    mus = data["traction"]["max_required_mu"]
    assert "wheel1" in mus and "wheel2" not in mus and "wheel5" not in mus
    assert "friction of wheel2, wheel5 not determined" in data["traction"]["summary"]

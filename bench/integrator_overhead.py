"""The compiled Adams integrator's own cost per step (robotdyn/_integrator.hpp, issue 26), without robotdyn's
evaluation: Quasimoro's 90 s 'rectilinear' manoeuvre integrated by the same driver (run_sampled, 1,801 samples from
the Hermite interpolant, a breakpoint at t = 1 s) on the closed-form reduced model of tests/oracles/quasimoro_sympy.py
compiled to C (sympy's cse and ccode): its evaluations, steps, the whole run's CPU time, the right-hand side's own
time (the same number of calls, timed alone), and the difference per step and per evaluation: what the integrator
adds to every evaluation of robotdyn's compiled model. The trajectory is the model's (it steps like robotdyn's
compiled run to within a few evaluations). Needs g++ and the build's headers (Boost.Odeint, Eigen from the cmeel
prefix). This is a benchmark, not a test: it asserts nothing.

Usage: python bench/integrator_overhead.py [--headers DIR] [rtol ...]   (default rtols 1e-10, 1e-8, 1e-6; atol = rtol
/ 100 as the bench's rows; DIR: another checkout's robotdyn/ holding its _integrator.hpp, for a side-by-side run)
"""

from __future__ import annotations

import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

DRIVER = r"""
#include "_integrator.hpp"
#include "quasimoro_model.hpp"
#include <Eigen/Dense>
#include <cstdio>
#include <cstdlib>
#include <ctime>
using namespace robotdyn;
static double cpu() { timespec a; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a); return a.tv_sec + 1e-9 * a.tv_nsec; }
static long nfev = 0;
// (q, nu) -> (S nu, M_r^-1 (B_r tau - h)), tau = 0.1 sin(pi t) on both motors for t <= 1 s
static void rhs(const State& x, State& dx, double t) {
  ++nfev;
  dx.resize(9);
  double Mr[9], hr[3], Br[6], S[18];
  quasimoro(x.data(), Mr, hr, Br, S);
  const double tau = (t >= 0.0 && t <= 1.0) ? 0.1 * std::sin(M_PI * t) : 0.0;
  for (int i = 0; i < 6; ++i) dx[i] = S[3 * i] * x[6] + S[3 * i + 1] * x[7] + S[3 * i + 2] * x[8];
  const Eigen::Matrix3d M = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(Mr);
  Eigen::Vector3d f;
  for (int i = 0; i < 3; ++i) f[i] = Br[2 * i] * tau + Br[2 * i + 1] * tau - hr[i];
  const Eigen::Vector3d a = M.llt().solve(f);
  for (int i = 0; i < 3; ++i) dx[6 + i] = a[i];
}
int main(int argc, char** argv) {
  const double rtol = std::atof(argv[1]), atol = rtol * 1e-2;
  auto system = [](const State& x, State& dx, double t) { rhs(x, dx, t); };
  std::vector<double> samples, breaks{1.0};
  for (int i = 0; i <= 1800; ++i) samples.push_back(0.05 * i);
  double best = 1e9, alone = 1e9;
  long evals = 0, steps = 0;
  for (int rep = 0; rep < 7; ++rep) {
    std::vector<double> ys;
    ys.reserve(1801 * 9);
    auto observer = [&](double, const State& x) { ys.insert(ys.end(), x.begin(), x.end()); };
    auto poll = [](double) { return true; };
    size_t next = 0;
    nfev = 0;
    double c = cpu();
    const Outcome out = integrate("adams", system, State(9, 0.0), 0.0, 90.0, samples, next, breaks, rtol, atol,
                                  observer, poll);
    best = std::min(best, cpu() - c);
    evals = nfev, steps = out.steps;
    State x = out.y, dx(9);
    c = cpu();
    for (long i = 0; i < evals; ++i) rhs(x, dx, 2.0 + 1e-9 * i);
    alone = std::min(alone, cpu() - c);
  }
  std::printf("%g %ld %ld %.6f %.6f\n", rtol, evals, steps, best, alone);
}
"""


def _include_dirs(headers: Path) -> list[str]:
    roots = [Path(p) for p in sys.path if p] + [Path(sysconfig.get_paths()["purelib"])]
    prefix = next((r / "cmeel.prefix" / "include" for r in roots if (r / "cmeel.prefix" / "include" / "boost").exists()),
                  None)
    if prefix is None:
        raise SystemExit("Boost.Odeint's headers (cmeel.prefix/include) not found")
    return [str(headers), str(prefix), str(prefix / "eigen3")]


def closed_form_header() -> str:
    """C++ of the Quasimoro closed-form model at the paper's parameters: quasimoro(q, Mr, hr, Br, S), y = (q, nu),
    row-major M_r (3, 3), h = C_r nu + g_r (3,), B_r (3, 2), S (6, 3)."""
    import sympy as sp

    sys.path.insert(0, str(ROOT / "tests"))
    from oracles import quasimoro_sympy as qo

    s = qo.symbolic_reduced("axle")
    p = qo.paper_defaults()
    values = {sym: p[k] for sym, k in zip(qo.PARAM_SYMS, qo.PARAM_KEYS)}
    exprs = [e.subs(values) for e in (*s["M_r"], *(s["C_r"] * sp.Matrix(qo.NU) + s["g_r"]), *s["B_r"], *s["S"])]
    names = {**{qo.Q[i]: sp.Symbol(f"q[{i}]") for i in range(6)}, **{qo.NU[i]: sp.Symbol(f"q[{6 + i}]") for i in range(3)}}
    subexpressions, reduced = sp.cse(exprs)
    lines = ["#pragma once", "#include <cmath>",
             "inline void quasimoro(const double* q, double* Mr, double* hr, double* Br, double* S) {"]
    lines += [f"  const double {a} = {sp.ccode(e.xreplace(names))};" for a, e in subexpressions]
    i = 0
    for name, n in (("Mr", 9), ("hr", 3), ("Br", 6), ("S", 18)):
        for j in range(n):
            lines.append(f"  {name}[{j}] = {sp.ccode(reduced[i].xreplace(names))};")
            i += 1
    return "\n".join(lines + ["}", ""])


def main(rtols: list[float], headers: Path = ROOT / "robotdyn") -> None:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "quasimoro_model.hpp").write_text(closed_form_header())
        (tmp / "driver.cpp").write_text(DRIVER)
        flags = ["-std=c++17", "-O2", "-DNDEBUG", "-ffp-contract=off", "-w"]  # setup.py's
        subprocess.run(["g++", *flags, f"-I{tmp}", *(f"-I{d}" for d in _include_dirs(headers)), str(tmp / "driver.cpp"),
                        "-o", str(tmp / "driver")], check=True)
        print(f"Adams ({headers / '_integrator.hpp'}) on Quasimoro's closed-form model, 90 s, 1,801 samples "
              "(best of 7):")
        print(f"{'rtol':>7} {'evals':>6} {'steps':>6} {'run [ms]':>9} {'rhs alone [ms]':>15} "
              f"{'integrator / step [us]':>23} {'/ evaluation [us]':>18}")
        for rtol in rtols:
            out = subprocess.run([str(tmp / "driver"), repr(rtol)], check=True, capture_output=True, text=True)
            r, evals, steps, run, alone = out.stdout.split()
            evals, steps, run, alone = int(evals), int(steps), float(run), float(alone)
            print(f"{float(r):>7g} {evals:>6d} {steps:>6d} {1e3 * run:>9.3f} {1e3 * alone:>15.3f} "
                  f"{1e6 * (run - alone) / steps:>23.3f} {1e6 * (run - alone) / evals:>18.3f}")


if __name__ == "__main__":
    args = sys.argv[1:]
    where = ROOT / "robotdyn"
    if args[:1] == ["--headers"]:
        where, args = Path(args[1]).resolve(), args[2:]
    main([float(a) for a in args] or [1e-10, 1e-8, 1e-6], where)

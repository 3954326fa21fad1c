"""Build of robotdyn's optional C++ extension ``robotdyn._compiled`` (everything else is in pyproject.toml).

The extension uses Pinocchio's C++ headers as installed by the ``pin`` wheel (its ``cmeel.prefix``), Eigen from
``cmeel-eigen`` and pybind11; all three are build requirements in pyproject.toml. Without a C++ compiler the build
of the extension is skipped (``optional``) and robotdyn runs on its Python path alone.

``make venv`` compiles the extension in place (``setup.py build_ext --inplace``, one CPU) while pip installs robotdyn
editable with ``ROBOTDYN_EXTENSION_IN_PLACE=1`` (no extension: it would compile it a second time) and its
dependencies on the other CPU.
"""

import os
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup


def _prefix_include(marker: str) -> list[str]:
    """The ``cmeel.prefix/include`` directories (of the build environment) that contain ``marker``."""
    roots = [Path(p) for p in sys.path if p] + [Path(sysconfig.get_paths()["purelib"])]
    return sorted({str(r / "cmeel.prefix" / "include") for r in roots if (r / "cmeel.prefix" / "include" / marker).exists()})


def _extension() -> list[Extension]:
    if os.environ.get("ROBOTDYN_EXTENSION_IN_PLACE") == "1":  # make venv compiles it in place beside pip (Makefile)
        return []
    try:
        import pybind11
    except ImportError:
        return []
    pinocchio, eigen = _prefix_include("pinocchio"), _prefix_include("eigen3")
    if not pinocchio or not eigen:
        return []
    return [
        Extension(
            "robotdyn._compiled",
            ["robotdyn/_compiled.cpp"],
            depends=["robotdyn/_integrator.hpp", "robotdyn/_torque_profile.hpp", "robotdyn/_controller.hpp",
                     "robotdyn/_stiff_integrator.hpp",
                     *sorted(p.as_posix() for p in Path("robotdyn/kernels").glob("*.hpp"))],  # the kernels
            include_dirs=[pybind11.get_include(), *pinocchio, *(str(Path(e) / "eigen3") for e in eigen)],
            define_macros=[
                ("NDEBUG", None),
                ("BOOST_MPL_LIMIT_LIST_SIZE", "30"),  # as Pinocchio's CMake config requires
                ("BOOST_MPL_LIMIT_VECTOR_SIZE", "30"),
                ("BOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", None),
                ("BOOST_FUSION_INVOKE_MAX_ARITY", "12"),
            ],
            extra_compile_args=["-std=c++17", "-O2", "-g0", "-fvisibility=hidden", "-w",
                                "-ffp-contract=off"],  # torque profiles: the same bits as in Python
            language="c++",
            optional=True,
        )
    ]


setup(ext_modules=_extension())

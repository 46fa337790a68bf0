"""The portable math of the Windows build and of builds from the FMUs' sources (fmu_src/native/portable_math.c).

Every function portable_math.c provides (the list is read from plant_math.h, so a new one is tested or this
fails) is held to a stated bound in ULP (units in the last place):

- against glibc's libm at 200 000 arguments (compiled into the same harness): the Linux binaries use glibc,
  so this is how far the Windows numbers may stray from the Linux ones;
- against the exact value (mpmath at 60 digits, rounded once to a double) at 3 000 arguments: glibc could
  share an error with ours, the exact value cannot.

The bounds are fdlibm's documented errors, whose methods portable_math.c follows: sin, cos, exp and log
below 1 ULP, so each result is one of the two doubles around the exact value (at most 1 ULP from the
correctly rounded one, and from glibc's, which is correctly rounded in practice); tanh within 3 ULP of
glibc's and of the exact value (fdlibm's tanh is built on expm1; glibc's is within 2 ULP). The arguments
cover what the models pass (swing angles, the planner's and the gust's phases, the sensor's uniform
numbers) and the ranges each method treats apart (argument reduction, tiny and huge arguments, the ends of
exp's range, subnormal logarithms).
"""

import random
import re
import subprocess

import numpy as np
import pytest
from native_fmus import compiler

from crane_fmu.build_scripts.native import MODELS_DIR

DECLARED = re.findall(r"double crane_(\w+)\(double x\);", (MODELS_DIR / "plant_math.h").read_text())
# function: (most ULP from glibc's, most ULP from the exact value)
BOUNDS = {"sin": (1, 1), "cos": (1, 1), "exp": (1, 1), "log": (1, 1), "tanh": (3, 3)}
AGREE = 0.8  # of the arguments at least, ours is glibc's: a systematic bias in the last bit shows at about half


@pytest.mark.quick
def test_every_portable_function_has_a_bound():
    assert sorted(DECLARED) == sorted(BOUNDS)


def _arguments(name, n):
    """``n`` arguments for ``name`` over the ranges its method treats apart, and its edge cases."""
    rng = random.Random(f"{name}-{n}")
    if name in ("sin", "cos"):
        xs = [rng.uniform(-3.5, 3.5) for _ in range(n // 2)]  # angles: no reduction up to pi/4, then by pi/2
        xs += [rng.uniform(-1, 1) * 10 ** rng.uniform(-9, 5) for _ in range(n // 2)]  # tiny to 1e5: reduction
        xs += [0.0, -0.0, 1e-300, 0.5, 1.0, 0.7853981633974483, 1.5707963267948966, 3.141592653589793, 1e5]
    elif name == "exp":
        xs = [rng.uniform(-1.5, 1.5) for _ in range(n // 2)]
        xs += [rng.uniform(-745, 709.7) for _ in range(n // 2)]
        xs += [0.0, 1e-10, -1e-10, 0.34657359027997264, 709.78, -708.4, -744.4, -745.0]
    elif name == "log":
        xs = [((rng.getrandbits(53) >> 11) + 0.5) / 2 ** 53 for _ in range(n // 2)]  # the Sensor's u1
        xs += [10 ** rng.uniform(-320, 308) for _ in range(n // 2)]
        xs += [5e-324, 1e-310, 0.5, 1.0, 1.0000001, 0.9999999, 2.0, 1e300]
    else:  # tanh
        xs = [rng.uniform(-1, 1) * 10 ** rng.uniform(-20, 1.7) for _ in range(n)]
        xs += [1e-300, 0.5, 1.0, 2.0, 22.0, -22.0, 1e300]
    return xs


HARNESS = r"""
#include <math.h>
#include <stdio.h>
#include <string.h>
double crane_%(name)s(double);
int main(void) {
    double x;
    while (scanf("%%la", &x) == 1) printf("%%a %%a\n", crane_%(name)s(x), %(name)s(x));
    return 0;
}
"""


def _ours_and_glibc(name, xs, folder):
    """``(ours, glibc's)`` at ``xs``: portable_math.c compiled as the Windows build compiles it, on Linux."""
    (folder / "harness.c").write_text(HARNESS % {"name": name})
    subprocess.run([compiler(), "-O2", "-Wall", "-Werror", "-ffp-contract=off", "-DCRANE_OWN_MATH", f"-I{MODELS_DIR}",
                    str(folder / "harness.c"), str(MODELS_DIR / "portable_math.c"), "-o", str(folder / "h"), "-lm"],
                   check=True)
    out = subprocess.run([str(folder / "h")], input="\n".join(x.hex() for x in xs), capture_output=True, text=True,
                         check=True).stdout
    values = np.array([[float.fromhex(v) for v in line.split()] for line in out.splitlines()])
    assert values.shape == (len(xs), 2)
    return values[:, 0], values[:, 1]


def _ulps(a, b):
    """ULP between doubles of one sign (as the integers of their bits are ordered), 0 where both are equal."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    assert np.all((np.signbit(a) == np.signbit(b)) | (a == b)), "a result of the wrong sign"
    return np.where(a == b, 0, np.abs(a.view(np.int64) - b.view(np.int64)))


@pytest.mark.parametrize("name", BOUNDS)
def test_the_portable_function_is_within_its_bound_of_glibcs(name, tmp_path):
    xs = _arguments(name, 200_000)
    ours, glibc = _ours_and_glibc(name, xs, tmp_path)
    most, _ = BOUNDS[name]
    ulps = _ulps(ours, glibc)
    worst = int(np.argmax(ulps))
    assert ulps[worst] <= most, f"crane_{name}({xs[worst]!r}) = {ours[worst]!r}, glibc {glibc[worst]!r}: " \
                                f"{ulps[worst]} ULP apart, more than {most}"
    assert np.count_nonzero(ulps) <= (1 - AGREE) * len(xs), f"{np.count_nonzero(ulps)} of {len(xs)} differ from glibc"


@pytest.mark.quick
@pytest.mark.parametrize("name", BOUNDS)
def test_the_portable_function_is_within_its_bound_of_the_exact_value(name, tmp_path):
    mpmath = pytest.importorskip("mpmath")
    xs = _arguments(name, 3_000)
    ours, _ = _ours_and_glibc(name, xs, tmp_path)
    function = getattr(mpmath, name)
    with mpmath.workdps(60):
        exact = np.array([float(function(mpmath.mpf(x))) for x in xs])  # rounded once, to nearest
    _, most = BOUNDS[name]
    ulps = _ulps(ours, exact)
    worst = int(np.argmax(ulps))
    assert ulps[worst] <= most, f"crane_{name}({xs[worst]!r}) = {ours[worst]!r}, exactly {exact[worst]!r}: " \
                                f"{ulps[worst]} ULP apart, more than {most}"

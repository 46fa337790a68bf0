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
glibc's and of the exact value (fdlibm's tanh is built on expm1; glibc's is within 2 ULP); atan below 1 ULP,
and atan2 (from it, by quadrant) within 2 ULP of glibc's in every quadrant. The arguments cover what the
models pass (swing angles, the planner's and the gust's phases, the sensor's uniform numbers) and the
ranges each method treats apart (argument reduction, tiny and huge arguments, the ends of
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
BOUNDS = {"sin": (1, 1), "cos": (1, 1), "exp": (1, 1), "log": (1, 1), "tanh": (3, 3), "atan": (1, 1)}
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
    elif name == "atan":  # the swing angle's atan2(horizontal, vertical) of a cable: |y / x| of any size
        xs = [rng.uniform(-3, 3) for _ in range(n // 2)]  # each of its reductions: 7/16, 11/16, 19/16, 39/16
        xs += [rng.choice((-1, 1)) * 10 ** rng.uniform(-20, 25) for _ in range(n // 2)]
        xs += [0.0, -0.0, 1e-300, 0.4375, 0.6875, 1.1875, 2.4375, 1.0, -1.0, 2.0 ** 66, 1e300]
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


HARNESS2 = r"""
#include <math.h>
#include <stdio.h>
double crane_atan2(double, double);
int main(void) {
    double y, x;
    while (scanf("%la %la", &y, &x) == 2) printf("%a %a\n", crane_atan2(y, x), atan2(y, x));
    return 0;
}
"""


def test_the_portable_atan2_is_within_two_ulp_of_glibcs_in_every_quadrant(tmp_path):
    """crane_atan2 is crane_atan (below 1 ULP) of |y / x| (one rounding) and the quadrant's pi with its tail: within
    2 ULP of glibc's, and exactly its special values (zeros, infinities, NaN, the axes)."""
    rng = random.Random(2)
    pairs = [(rng.choice((-1, 1)) * 10 ** rng.uniform(-10, 10), rng.choice((-1, 1)) * 10 ** rng.uniform(-10, 10))
             for _ in range(40_000)]
    pairs += [(rng.uniform(0, 1), rng.uniform(-1, 1)) for _ in range(20_000)]  # a cable's (horizontal, vertical)
    special = [0.0, -0.0, 1.0, -1.0, float("inf"), -float("inf"), 1e300, 5e-324]
    pairs += [(y, x) for y in special for x in special] + [(float("nan"), 1.0), (1.0, float("nan"))]
    (tmp_path / "harness.c").write_text(HARNESS2)
    subprocess.run([compiler(), "-O2", "-Wall", "-Werror", "-ffp-contract=off", "-DCRANE_OWN_MATH", f"-I{MODELS_DIR}",
                    str(tmp_path / "harness.c"), str(MODELS_DIR / "portable_math.c"), "-o", str(tmp_path / "h"), "-lm"],
                   check=True)
    out = subprocess.run([str(tmp_path / "h")], input="\n".join(f"{y.hex()} {x.hex()}" for y, x in pairs),
                         capture_output=True, text=True, check=True).stdout
    ours, glibc = np.array([[float.fromhex(v) for v in line.split()] for line in out.splitlines()]).T
    assert len(ours) == len(pairs)
    same_nan = np.isnan(ours) == np.isnan(glibc)
    assert same_nan.all()
    finite = ~np.isnan(glibc)
    ulps = _ulps(ours[finite], glibc[finite])
    assert ulps.max() <= 2, pairs[int(np.flatnonzero(finite)[np.argmax(ulps)])]
    exact = [i for i, (y, x) in enumerate(pairs) if not (np.isfinite(y) and np.isfinite(x) and y and x)]
    assert all(ours[i].hex() == glibc[i].hex() or np.isnan(glibc[i]) for i in exact)

"""Study files: what to vary, how long to simulate, what to keep.

A study is a TOML (or, with PyYAML installed, YAML) file::

    system = "paper"                 # a built-in system's name or an SSP file (default paper)
    stop_time = 10.0                 # [s], required
    step = 0.002                     # communication step [s], required
    algorithm = "gauss-seidel"       # the master algorithm, or "jacobi", "iterative-jacobi"
    metrics = ["outcome", "settling_0.5deg_s"]   # default: every metric of the system's plant (metric_names)
    settling_band_deg = 0.25         # band of the metric "settling_band_s" (default 0.5)

    [parameters]                     # the grid: every combination of the listed values
    "plant.theta1_0" = [0.0349, 0.0873, 0.1745]
    "plant.l1, controller.l1" = {start = 0.5, stop = 1.5, num = 3}   # one axis, both variables
    "controller.K2_theta2" = {low = 100.0, high = 400.0}             # sampled, see [sampling]

    [sampling]                       # only when a parameter is sampled
    method = "latin-hypercube"       # or "random"
    samples = 20
    seed = 1

    [fixed]                          # set in every case
    "controller.w_theta2" = 0.0

    [use]                            # optional: your FMU (or law file) in an instance's place
    controller = "build/mine/PdSway.fmu"   # a path from the folder the sweep runs in, as --use

    [plot]                           # optional: metric over two parameters
    metric = "settling_0.5deg_s"
    x = "plant.theta1_0"
    y = "plant.l1"

Parameter names are ``INSTANCE.VARIABLE`` with an instance of the system, or ``crane.l1`` (the crane's own,
set on every instance that models it and that the case gives no value of its own: crane_fmu/crane_parameters.py).
Every mistake raises ``ValueError`` with one line naming the key and the rule.
"""

import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from crane_fmu import DEFAULT_SYSTEM
from crane_fmu.cosim.algorithms import ALGORITHMS
from crane_fmu.cosim.master import communication_points

METRICS = ("outcome", "settling_band_s", "settling_0.5deg_s", "settling_0.1deg_s", "max_theta1_deg", "max_theta2_deg",
           "rms_theta1_deg", "residual_after_15s_deg", "trolley_excursion_m", "trolley_final_m", "peak_abs_u",
           "end_time_s")  # the planar crane's: metric_names(CranePlant's roles)


def metric_names(crane):
    """The metrics of a study of a plant, by its roles (:class:`~crane_fmu.model.component.Crane`): the swing's
    figures named after its swing angles (``max_theta1_deg``; the spatial crane's ``max_swing1_deg``), the
    trolley's and the demand's along its first axis."""
    return ("outcome", "settling_band_s", "settling_0.5deg_s", "settling_0.1deg_s",
            *(f"max_{name}_deg" for name in crane.swing), f"rms_{crane.swing[0]}_deg", "residual_after_15s_deg",
            "trolley_excursion_m", "trolley_final_m", "peak_abs_u", "end_time_s")


def known_metrics():
    """Every registered plant's :func:`metric_names`, in order, once each."""
    from crane_fmu import components

    return tuple(dict.fromkeys(name for plant in components.registered("plant") if plant.crane
                               for name in metric_names(plant.crane)))
SAMPLING = ("latin-hypercube", "random")
BUILTIN_DIR = Path(__file__).parent / "builtin"


@dataclass(frozen=True)
class Study:
    """A parsed study file."""

    stop_time: float
    step: float
    algorithm: str = "gauss-seidel"
    system: str = DEFAULT_SYSTEM
    metrics: tuple = METRICS  # as given; the system's plant's every metric when not (every_metric)
    settling_band_deg: float = 0.5
    grid: dict = field(default_factory=dict)  # axis name -> (variable names, values)
    sampled: dict = field(default_factory=dict)  # axis name -> (variable names, low, high)
    sampling: str = "latin-hypercube"
    samples: int = 0
    seed: int = 0
    fixed: dict = field(default_factory=dict)  # variable -> value
    plot: dict = field(default_factory=dict)
    use: dict = field(default_factory=dict)  # instance -> FMU file or law file in its place
    every_metric: bool = True  # no metrics given: every metric of the system's plant

    def metrics_of(self, crane, system="the system"):
        """The metrics a row of this study has for a plant's ``crane`` roles: those given, each one of the plant's
        (:func:`metric_names`), else all of the plant's; ValueError (one line) names one it has not."""
        names = metric_names(crane)
        if self.every_metric:
            return names
        for name in self.metrics:
            if name not in names:
                raise ValueError(f"metrics: {name} is no metric of {system}'s plant; its metrics: {', '.join(names)}")
        return self.metrics

    def cases(self):
        """Every case as ``{"instance.variable": value}``, in a reproducible order."""
        return list(self.iter_cases())

    def iter_cases(self):
        """The cases of :meth:`cases`, one at a time (a study of any size: only its samples are held, as numbers)."""
        grid_axes = list(self.grid.values())
        sample_points = self._samples() if self.sampled else [()]
        for point in itertools.product(*(values for _, values in grid_axes)):
            for sample in sample_points:
                case = dict(self.fixed)
                for (names, _), value in zip(grid_axes, point):
                    case.update(dict.fromkeys(names, value))
                for (names, _, _), value in zip(self.sampled.values(), sample):
                    case.update(dict.fromkeys(names, float(value)))
                yield case

    def case_count(self):
        """How many cases :meth:`cases` gives."""
        return math.prod(len(values) for _, values in self.grid.values()) * (self.samples if self.sampled else 1)

    def _samples(self):
        if not self.sampled:
            return []
        import numpy as np  # only a sampled study needs them: scipy.stats takes about 2.5 s to import
        from scipy.stats import qmc

        bounds = list(self.sampled.values())
        if self.sampling == "random":
            unit = np.random.default_rng(self.seed).random((self.samples, len(bounds)))
        else:
            unit = qmc.LatinHypercube(d=len(bounds), seed=self.seed).random(self.samples)
        lows, highs = (np.array([b[i] for b in bounds]) for i in (1, 2))
        return lows + unit * (highs - lows)  # each row a sample, the same numbers as lo + u * (hi - lo) one by one

    def settings(self):
        return {"system": self.system, "stop_time": self.stop_time, "step": self.step, "algorithm": self.algorithm,
                "settling_band_deg": self.settling_band_deg}


def case_id(case, settings):
    """A stable identifier of one case: its values and the run settings."""
    text = json.dumps({"case": case, "settings": settings}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _number(key, value, rule="a finite number"):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{key} must be {rule}, got {value!r}")
    return float(value)


def _names(key):
    names = [n.strip() for n in key.split(",")]
    for name in names:
        instance, dot, variable = name.partition(".")
        if not dot or not variable or not instance:
            raise ValueError(f"parameter {name!r} must be INSTANCE.VARIABLE")
    return tuple(names)


def _axis(key, value):
    """A [parameters] entry: ("grid", values) or ("sampled", (low, high))."""
    if isinstance(value, list):
        if not value:
            raise ValueError(f"parameters.{key!r} must list at least one value")
        return "grid", [v if isinstance(v, str) else _number(f"parameters.{key!r} value", v) for v in value]
    if isinstance(value, dict) and set(value) == {"start", "stop", "num"}:
        num = value["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ValueError(f"parameters.{key!r}.num must be a whole number >= 1, got {num!r}")
        start = _number(f"parameters.{key!r}.start", value["start"])
        stop = _number(f"parameters.{key!r}.stop", value["stop"])
        return "grid", [start + (stop - start) * i / (num - 1) for i in range(num)] if num > 1 else [start]
    if isinstance(value, dict) and set(value) == {"low", "high"}:
        low = _number(f"parameters.{key!r}.low", value["low"])
        high = _number(f"parameters.{key!r}.high", value["high"])
        if not high > low:
            raise ValueError(f"parameters.{key!r}.high must be > low {low!r}, got {high!r}")
        return "sampled", (low, high)
    raise ValueError(f"parameters.{key!r} must be a list of values, {{start, stop, num}} or {{low, high}}, "
                     f"got {value!r}")


def parse(data, source="study"):
    """Build a :class:`Study` from the loaded file contents (a dict)."""
    known = {"system", "stop_time", "step", "algorithm", "metrics", "parameters", "sampling", "fixed", "plot",
             "settling_band_deg", "use"}
    if "master" in data and "algorithm" not in data:  # the key's former name
        data = {("algorithm" if key == "master" else key): value for key, value in data.items()}
    if "controller" in data:
        raise ValueError(f"{source}: the key controller is gone: name the system instead, system = \"free\" for the "
                         "plant alone (controller = false) or system = \"paper\" (controller = true)")
    unknown = sorted(set(data) - known)
    if unknown:
        raise ValueError(f"{source}: unknown key {unknown[0]!r}; known keys: {', '.join(sorted(known))}")
    for key in ("stop_time", "step"):
        if key not in data:
            raise ValueError(f"{source}: {key} is required")
    stop_time = _number("stop_time", data["stop_time"], "a number > 0")
    step = _number("step", data["step"], "a number > 0")

    communication_points(0.0, stop_time, step)
    algorithm = data.get("algorithm", "gauss-seidel")
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    system = data.get("system", DEFAULT_SYSTEM)
    if not isinstance(system, str) or not system:
        raise ValueError(f"system must be a system's name or an SSP file, got {system!r}")
    listed = data.get("metrics", [])
    if not (isinstance(listed, list) and all(isinstance(m, str) for m in listed)):
        raise ValueError(f"metrics must be a list of metric names, got {data['metrics']!r}")
    metrics = tuple(data.get("metrics", METRICS))
    known = known_metrics()
    for m in metrics:
        if m not in known:
            raise ValueError(f"metrics: unknown metric {m!r}; known: {', '.join(known)}")

    band = _number("settling_band_deg", data.get("settling_band_deg", 0.5), "a number > 0")
    if not band > 0:
        raise ValueError(f"settling_band_deg must be a number > 0, got {band!r}")

    grid, sampled, named = {}, {}, set()
    for key, value in data.get("parameters", {}).items():
        names = _names(key)
        twice = named.intersection(names) or {n for n in names if names.count(n) > 1}
        if twice:
            raise ValueError(f"parameter {sorted(twice)[0]} is varied twice (parameters.{key!r}); vary it once")
        named.update(names)
        kind, spec = _axis(key, value)
        if kind == "grid":
            grid[key] = (names, spec)
        else:
            sampled[key] = (names, *spec)
    sampling = data.get("sampling", {})
    method = sampling.get("method", "latin-hypercube")
    if method not in SAMPLING:
        raise ValueError(f"sampling.method must be one of {', '.join(SAMPLING)}, got {method!r}")
    samples = sampling.get("samples", 0)
    if sampled and (isinstance(samples, bool) or not isinstance(samples, int) or samples < 1):
        raise ValueError(f"sampling.samples must be a whole number >= 1 when a parameter is sampled, got {samples!r}")
    seed = sampling.get("seed", 0)
    fixed = {}
    for key, value in data.get("fixed", {}).items():
        for name in _names(key):
            fixed[name] = value if isinstance(value, str) else _number(f"fixed.{key!r}", value)
    plot = dict(data.get("plot", {}))
    if plot:
        if plot.get("metric") not in known:
            raise ValueError(f"plot.metric must be one of {', '.join(known)}, got {plot.get('metric')!r}")
        axes = {n for names, *_ in list(grid.values()) + list(sampled.values()) for n in names}
        for axis in ("x", "y"):
            if plot.get(axis) not in axes:
                raise ValueError(f"plot.{axis} must be a varied parameter ({', '.join(sorted(axes))}), "
                                 f"got {plot.get(axis)!r}")
    use = data.get("use", {})
    if not isinstance(use, dict) or not all(isinstance(v, str) and v for v in use.values()):
        raise ValueError(f"use must be a table of INSTANCE = \"FILE.fmu\", got {use!r}")
    return Study(stop_time, step, algorithm, system, metrics, band, grid, sampled, method, samples, seed, fixed,
                 plot, dict(use), every_metric="metrics" not in data)


def load(path):
    """Read a study file (TOML, or YAML when PyYAML is installed); ``builtin:NAME`` for a shipped study."""
    text_path = str(path)
    if text_path.startswith("builtin:"):
        name = text_path.split(":", 1)[1]
        path = BUILTIN_DIR / f"{name.replace('-', '_')}.toml"
        if not path.is_file():
            names = ", ".join(p.stem.replace("_", "-") for p in sorted(BUILTIN_DIR.glob("*.toml")))
            raise ValueError(f"no built-in study {name!r}; built-in studies: {names}")
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"cannot read study file {path}: {exc.strerror}") from None
    if path.suffix in (".yaml", ".yml"):
        try:
            import yaml  # optional: PyYAML
        except ImportError:
            raise ValueError(f"{path}: YAML study files need PyYAML (pip install pyyaml)") from None
        try:
            data = yaml.safe_load(raw)
        except yaml.YAMLError as exc:
            raise ValueError(f"{path}: not valid YAML ({str(exc).splitlines()[0]})") from None
    else:
        try:
            import tomllib
        except ImportError:  # Python 3.10
            import tomli as tomllib
        try:
            data = tomllib.loads(raw.decode("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"{path}: not valid TOML ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: a study file holds keys and values, got {type(data).__name__}")
    return parse(data, str(path))

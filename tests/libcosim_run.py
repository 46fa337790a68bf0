"""Run a system file with libcosim and print the plant's x, theta1, theta2 (or NAMES) as JSON (used by the tests).

usage: python libcosim_run.py ssp|osp PATH STEPS [INSTANCE [NAMES]]   (NAMES: comma-separated)
"""

import json
import sys

from libcosimpy.CosimEnums import CosimVariableType
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

log_output_level(CosimLogLevel.ERROR)
kind, path, steps = sys.argv[1], sys.argv[2], int(sys.argv[3])
instance = sys.argv[4] if len(sys.argv) > 4 else "plant"
names = sys.argv[5].split(",") if len(sys.argv) > 5 else ["x", "theta1", "theta2"]
if kind == "ssp":
    execution = CosimExecution.from_ssp_file(path, step_size=1_000_000)  # 1 ms in ns
else:
    execution = CosimExecution.from_osp_config_file(path)
plant = [s.index for s in execution.slave_infos() if s.name.decode() == instance][0]
refs = {v.name.decode(): v.reference for v in execution.slave_variables(plant)}
observer = CosimObserver.create_time_series(buffer_size=steps + 10)
execution.add_observer(observer)
for name in names:
    observer.start_time_series(plant, refs[name], CosimVariableType.REAL)
execution.simulate_until(target_time=steps * 1_000_000)
series = {}
for name in names:
    times, _, values = observer.time_series_real_samples(plant, refs[name], from_step=0, sample_count=steps + 5)
    series[name] = [[t * 1e-9 for t in times], list(values)]
print(json.dumps(series))

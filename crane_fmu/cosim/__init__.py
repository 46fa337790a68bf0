"""Co-simulation master on fmpy: FMU instances, connections, stepping, recorders."""

from .fmi import FmiError, FmuInstance
from .master import MODES, Connection, Master
from .recorder import ArrayRecorder, CsvRecorder, read_csv, write_csv
from .system import CRANE_CONNECTIONS, crane_system, simulate

__all__ = ["FmiError", "FmuInstance", "MODES", "Connection", "Master", "ArrayRecorder",
           "CsvRecorder", "read_csv", "write_csv", "CRANE_CONNECTIONS", "crane_system", "simulate"]

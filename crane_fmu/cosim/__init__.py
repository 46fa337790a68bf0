"""A general co-simulation library on fmpy: instances, systems as data, master, recorders, SSP/OSP."""

from .instance import FmiError, open_instance
from .master import MODES, Connection, Master
from .recorder import ArrayRecorder, CsvRecorder, ParquetRecorder, read_csv, read_result, recorder_for, write_csv
from .system import System, connect, run, simulate

__all__ = ["FmiError", "open_instance", "MODES", "Connection", "Master", "ArrayRecorder", "CsvRecorder",
           "ParquetRecorder", "read_csv", "read_result", "recorder_for", "write_csv", "System", "connect", "run",
           "simulate"]

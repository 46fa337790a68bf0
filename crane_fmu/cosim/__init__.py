"""A general co-simulation library on fmpy: instances, systems as data, master, recorders, SSP/OSP."""

from .adapters import open_instance
from .connections import Connection, connect
from .instance import FmiError
from .master import Master
from .recorder import (
                       ArrayRecorder,
                       CsvRecorder,
                       MatRecorder,
                       ParquetRecorder,
                       ProgressLine,
                       cut_short_path,
                       read_csv,
                       read_result,
                       recorder_for,
                       write_csv,
)
from .system import System, run, simulate

__all__ = ["FmiError", "open_instance", "Connection", "Master", "ArrayRecorder", "CsvRecorder", "MatRecorder",
           "ParquetRecorder", "ProgressLine", "cut_short_path", "read_csv", "read_result", "recorder_for",
           "write_csv", "System", "connect", "run", "simulate"]

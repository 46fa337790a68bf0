"""An FMU's shared library checked before it is loaded: a truncated one must be one line, not a crash.

The dynamic loader maps an ELF library's segments from the file; a file cut short (a copy interrupted, a
disk that filled) maps pages past its end, and the first touch of one is SIGBUS: the process dies with no
word ("Bus error", status 135) and no signal handler can turn that into a message. Reading the headers
first is exact and costs microseconds: the file must hold every byte its program headers (the segments the
loader maps) and section headers say it has. Loading in a child process first would also catch what no
header shows, but would cost a process start for every FMU of every case; a truncated copy is the fault met in
practice (issue 49), and it is what the headers see.
"""

import os
import struct
from pathlib import Path

ELF = b"\x7fELF"


def check_library(path, fmu=None):
    """ValueError (one line naming the FMU and the file) if the ELF library at ``path`` is shorter than its
    headers say or too short to have them. Libraries of other formats (PE, Mach-O) are not looked at."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(64)
        if head[:4] != ELF:
            if len(head) < 4 and Path(path).suffix == ".so":
                raise ValueError(_truncated(path, fmu, size, 64))
            return
        bits64, order = head[4] == 2, "<" if head[5] == 1 else ">"
        if len(head) < (64 if bits64 else 52):
            raise ValueError(_truncated(path, fmu, size, 64 if bits64 else 52))
        if bits64:
            ph_offset, sh_offset = struct.unpack_from(order + "QQ", head, 32)
            ph_size, ph_count, sh_size, sh_count = struct.unpack_from(order + "HHHH", head, 54)
        else:
            ph_offset, sh_offset = struct.unpack_from(order + "II", head, 28)
            ph_size, ph_count, sh_size, sh_count = struct.unpack_from(order + "HHHH", head, 42)
        need = max(ph_offset + ph_size * ph_count, sh_offset + sh_size * sh_count)
        if size < need:
            raise ValueError(_truncated(path, fmu, size, need))
        f.seek(ph_offset)
        headers = f.read(ph_size * ph_count)
    for i in range(ph_count):  # each segment's bytes in the file: p_offset + p_filesz
        if bits64:
            offset, filesz = struct.unpack_from(order + "Q16xQ", headers, i * ph_size + 8)
        else:
            offset, filesz = struct.unpack_from(order + "I8xI", headers, i * ph_size + 4)
        need = max(need, offset + filesz)
    if size < need:
        raise ValueError(_truncated(path, fmu, size, need))


def _truncated(path, fmu, size, need):
    where = f"{fmu}: its binary {Path(path).name}" if fmu else str(path)
    return (f"{where} is truncated ({size} bytes, its headers need {need}): build or copy the FMU again")

"""The allocator setting of the invflame command."""

import platform
import subprocess
import sys

import pytest

from invflame.process_memory import configure_malloc

GLIBC = platform.libc_ver()[0] == "glibc"

# Page faults of a 64 MiB block written, freed, and allocated and written again, in a process
# of its own (the setting is the whole process's and cannot be undone); C's malloc, as XLA's
# buffers are (NumPy asks for huge pages, which fault less).
_REFAULTS = """
import ctypes, resource, sys
from invflame.process_memory import configure_malloc
if sys.argv[1] == "keep":
    assert configure_malloc()
libc = ctypes.CDLL("libc.so.6")
libc.malloc.restype = ctypes.c_void_p
libc.free.argtypes = [ctypes.c_void_p]
size = 2**26
libc.free(ctypes.memset(libc.malloc(size), 1, size))
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
ctypes.memset(libc.malloc(size), 1, size)
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _refaults(setting: str) -> int:
    run = subprocess.run([sys.executable, "-c", _REFAULTS, setting], capture_output=True,
                         text=True, check=True)
    return int(run.stdout)


def test_glibc_takes_the_settings_and_other_c_libraries_are_left_alone():
    assert configure_malloc(keep_freed=False) is GLIBC


@pytest.mark.skipif(not GLIBC, reason="the setting is glibc's")
def test_a_freed_block_is_reused_without_page_faults():
    # glibc's defaults map a block this large afresh: a fault per 4 KiB page of its 64 MiB
    assert _refaults("default") > 10_000
    assert _refaults("keep") < 100


def test_fewer_than_one_arena_is_refused():
    with pytest.raises(ValueError, match="at least 1"):
        configure_malloc(0)

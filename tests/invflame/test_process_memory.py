"""The allocator setting of the invflame command."""

import platform

from invflame.process_memory import map_large_blocks


def test_glibc_takes_the_threshold_and_other_c_libraries_are_left_alone():
    assert map_large_blocks() is (platform.libc_ver()[0] == "glibc")

"""The allocator setting of the invflame command."""

import platform

import pytest

from invflame.process_memory import limit_malloc_arenas


def test_glibc_takes_the_arena_limit_and_other_c_libraries_are_left_alone():
    assert limit_malloc_arenas() is (platform.libc_ver()[0] == "glibc")


def test_fewer_than_one_arena_is_refused():
    with pytest.raises(ValueError, match="at least 1"):
        limit_malloc_arenas(0)

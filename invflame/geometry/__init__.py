"""Geometry: the voxel grid, pinhole cameras, camera rigs and ray–voxel traversal."""

from invflame.geometry.camera import PinholeCamera, framing_sensor_size
from invflame.geometry.coverage import common_view, crossed_voxels, ray_coverage
from invflame.geometry.grid import VoxelGrid
from invflame.geometry.rig import CameraRig, paper_rig, ring_rig
from invflame.geometry.traversal import RaySegments, ray_box_intersection, traverse

__all__ = [
    "CameraRig",
    "PinholeCamera",
    "RaySegments",
    "VoxelGrid",
    "common_view",
    "crossed_voxels",
    "framing_sensor_size",
    "paper_rig",
    "ray_box_intersection",
    "ray_coverage",
    "ring_rig",
    "traverse",
]

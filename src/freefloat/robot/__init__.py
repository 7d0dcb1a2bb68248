"""The robot: a spacecraft-plus-arm URDF loaded as a free floater, and servicer composition."""

from .model import Joint, Robot, load_robot, resolve_robot, robots_dir, shipped_robots

__all__ = ["Joint", "Robot", "load_robot", "resolve_robot", "robots_dir", "shipped_robots"]

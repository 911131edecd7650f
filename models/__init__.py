"""rast5d workloads: the Scene type, mesh loading, procedural and named scenes, YAML scene files."""
from .loader import load
from .mesh import load_mesh
from .registry import named, register_scene, scene_names
from .scene import Scene, SceneError

__all__ = ["Scene", "SceneError", "load", "load_mesh", "named", "scene_names", "register_scene"]

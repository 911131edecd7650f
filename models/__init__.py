"""rast5d workloads: the Scene type, mesh loading, procedural and named scenes, YAML scene files,
Mitsuba XML and glTF importers."""
from .framing import frame_hint
from .gltf import load_gltf
from .loader import load
from .mesh import load_mesh
from .mitsuba import SceneImportWarning, load_mitsuba
from .registry import named, register_scene, scene_names
from .scene import Scene, SceneError

__all__ = ["Scene", "SceneError", "SceneImportWarning", "load", "load_mesh", "load_mitsuba", "load_gltf",
           "frame_hint", "named", "scene_names", "register_scene"]

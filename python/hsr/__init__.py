"""hsr: exact depth, face-id, instance and barycentric images of meshes on the CPU (docs/python.md).

The package re-exports its C++ extension (hsr._hsr): hsr.load, hsr.Scene, hsr.Camera, hsr.render and
the rest, with Scene.from_open3d and Scene.from_trimesh (hsr.meshes). Python modules beside it are
imported on their own: hsr.distributed (Dask distributed).
"""
from . import _hsr
from ._hsr import *  # noqa: F401,F403 (the module's public names)
from ._hsr import __version__  # noqa: F401

# Classes named as users import them (hsr.Camera, not hsr._hsr.Camera): repr, help and pickle.
for _cls in (_hsr.Scene, _hsr.Camera):
    _cls.__module__ = __name__
del _cls

# Scenes from Open3D and trimesh meshes (duck-typed; neither library is imported).
from . import meshes as _meshes  # noqa: E402

_hsr.Scene.from_open3d = staticmethod(_meshes.from_open3d)
_hsr.Scene.from_trimesh = staticmethod(_meshes.from_trimesh)

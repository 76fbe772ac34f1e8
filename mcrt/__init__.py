"""mcrt: a Dr.Jit Monte-Carlo path tracer for the hexagonal room, validated against Mitsuba 3.

Importing mcrt sets ``DRJIT_LIBLLVM_PATH`` to a libLLVM that Dr.Jit accepts
(see :mod:`mcrt.llvm`) before anything imports drjit.
"""

from mcrt.llvm import find_llvm as _find_llvm

_find_llvm()

__version__ = "0.1.0"

from mcrt.scene import CANONICAL, Scene, SceneError, load_scene  # noqa: E402

__all__ = ["CANONICAL", "Scene", "SceneError", "load_scene", "__version__"]

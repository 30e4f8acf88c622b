"""Pick a headless OpenGL backend for MuJoCo before it is imported: EGL, else OSMesa.

MuJoCo reads MUJOCO_GL once, at import, so the choice must happen first. A user's explicit
MUJOCO_GL is respected. The probe runs in a subprocess (a failed EGL init can abort a process)
and its answer is exported so child processes (workers) skip it.
"""

from __future__ import annotations

import os
import subprocess
import sys

_PROBE = "from mujoco.{mod} import GLContext; c = GLContext(8, 8); c.make_current(); c.free()"


def _works(backend: str) -> bool:
    env = dict(os.environ, MUJOCO_GL=backend, PYOPENGL_PLATFORM=backend)
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _PROBE.format(mod=backend)],
            env=env,
            capture_output=True,
            timeout=60,
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return proc.returncode == 0


def select_backend() -> str | None:
    """Set MUJOCO_GL (and PYOPENGL_PLATFORM) to the first backend that works; return it."""
    if os.environ.get("MUJOCO_GL"):
        return os.environ["MUJOCO_GL"]
    if sys.platform != "linux":
        return None  # macOS / Windows use their native context
    for backend in ("egl", "osmesa"):
        if _works(backend):
            os.environ["MUJOCO_GL"] = backend
            os.environ.setdefault("PYOPENGL_PLATFORM", backend)
            return backend
    return None

"""Modal matching of deformable objects in dynamic pedobarography.

Python bindings of the pedomatch Rust workspace: numpy arrays in, numpy arrays out.
"""

from ._pymodal import *  # noqa: F401,F403
from ._pymodal import __version__  # noqa: F401
from ._pymodal import _options  # type: ignore[attr-defined]  # noqa: F401

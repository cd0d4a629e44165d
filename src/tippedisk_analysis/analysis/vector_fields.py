"""Moved to :mod:`tippedisk_analysis.dynamics.tensors` (``CompiledField`` is ``Field`` there); this old
import path keeps working for now."""

from ..dynamics.tensors import Field as CompiledField  # noqa: F401
from ..dynamics.tensors import bilinear, trilinear  # noqa: F401

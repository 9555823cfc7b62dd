"""MoDD generators: from a model to the files each role downloads.

>>> from modd_model import load_model
>>> from modd_gen import generate
>>> files = generate(load_model("mission.modd"), role="integrator")   # doctest: +SKIP
>>> [f.path for f in files][:2]                                       # doctest: +SKIP
['integrator/pub_1-driver/CMakeLists.txt', 'integrator/pub_1-driver/README.md']
"""

from .artifact import Artifact, Ownership, write_artifacts
from .generate import ROLES, generate

__all__ = ["Artifact", "Ownership", "ROLES", "generate", "write_artifacts"]

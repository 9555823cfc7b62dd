"""The MoDD workbench service: model store, live plan, deploy, stream proxy,
archives, roles.

>>> from modd_backend import Settings, create_app
>>> app = create_app(Settings(data_dir=Path("/tmp/modd-data")))   # doctest: +SKIP
"""

from .app import create_app
from .settings import Settings

__all__ = ["Settings", "create_app"]

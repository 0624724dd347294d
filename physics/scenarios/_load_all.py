"""Imports every scenario module so that the registry is complete. Add new modules here."""
from . import free_body  # noqa: F401
from . import three_body  # noqa: F401
from . import precession  # noqa: F401
from . import libration  # noqa: F401
from . import hyperion  # noqa: F401
from . import earth_precession  # noqa: F401
from . import moon  # noqa: F401

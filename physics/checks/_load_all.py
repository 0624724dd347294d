"""Every module that registers check rows. Add new modules here."""
from . import free_body  # noqa: F401
from . import libration  # noqa: F401
from . import three_body  # noqa: F401
from . import precession  # noqa: F401

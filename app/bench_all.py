"""Every module that registers benchmarks. Add new modules here."""
from . import bench_free_body  # noqa: F401
from . import bench_libration  # noqa: F401
from . import bench_three_body  # noqa: F401
from . import bench_precession  # noqa: F401
from . import bench_app  # noqa: F401
from . import bench_classroom  # noqa: F401

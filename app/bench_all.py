"""Every module that registers benchmarks. Add new modules here."""
from . import bench_free_body  # noqa: F401

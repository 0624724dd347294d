"""Per-scenario additions to the scene: each module registers `SceneExtra` subclasses with
`app.scene.register_extra`. Add new modules to the import list below."""
from importlib import import_module

_MODULES: list[str] = ["ch16"]  # e.g. "ch16", "three_body"

for _m in _MODULES:
    import_module(f"{__name__}.{_m}")

"""`python -m theoria …` is the `theoria` command."""
from theoria.app.cli import main

if __name__ == "__main__":  # not again in a sweep's worker, which imports this module on its way in
    raise SystemExit(main())

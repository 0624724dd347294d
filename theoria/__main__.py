"""`python -m theoria …` is the `theoria` command."""
from theoria.app.cli import main

if __name__ == "__main__":  # the command when run; importing the module runs nothing
    raise SystemExit(main())

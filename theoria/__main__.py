"""`python -m theoria …` is the `theoria` command."""
from theoria.app.cli import main

raise SystemExit(main())

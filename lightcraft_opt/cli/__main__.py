"""``python -m lightcraft_opt.cli``: the ``lightcraft`` command."""

from lightcraft_opt.cli.main import main

raise SystemExit(main())

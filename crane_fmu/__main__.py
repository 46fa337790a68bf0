"""``python -m crane_fmu``: the ``crane-fmu`` command."""

from crane_fmu.cli import main

raise SystemExit(main())

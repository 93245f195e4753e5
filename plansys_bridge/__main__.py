"""``python -m plansys_bridge`` runs the command line."""

from plansys_bridge.cli import main

raise SystemExit(main())

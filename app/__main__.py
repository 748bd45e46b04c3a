"""``python -m app`` runs the same command-line interface as ``bosun``."""

from app.cli import main

raise SystemExit(main())

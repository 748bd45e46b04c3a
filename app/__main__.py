"""``python -m app`` runs the same command-line interface as ``bosun``."""

from app.launch import main

raise SystemExit(main())

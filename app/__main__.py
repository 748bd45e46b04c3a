"""``python -m app`` runs the same command-line interface as ``bosun``."""

try:  # Ctrl-C while app.launch itself loads: the same one line and status 130 (app.launch.main answers after)
    from app.launch import main
except KeyboardInterrupt:
    import sys

    print("bosun: interrupted", file=sys.stderr)
    raise SystemExit(130) from None

raise SystemExit(main())

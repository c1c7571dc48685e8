"""``python -m surrogate_rbrdo ...`` is the ``rbrdo`` command (no PATH set-up needed)."""

from surrogate_rbrdo.runner.cli import main

if __name__ == "__main__":
    raise SystemExit(main())

"""``python -m supercoil``: the ``supercoil`` command (:mod:`supercoil.cli.main`)."""

from supercoil.cli.main import main

if __name__ == "__main__":
    main()

"""``python -m ocio_vp``: the same as the ``ocio-vp`` command."""

import sys

from ocio_vp.cli import main

if __name__ == "__main__":
    sys.exit(main())

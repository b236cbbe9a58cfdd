"""``python -m fabrication.cli`` runs the ``ppfab`` command."""

import sys

from . import main

sys.exit(main())

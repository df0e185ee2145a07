"""``python -m husky_course``: see :mod:`husky_course.cli`."""

from .cli import main

raise SystemExit(main())

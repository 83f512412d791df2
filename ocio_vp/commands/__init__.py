"""One module per ``ocio-vp`` verb.

Each module defines ``add_parser(subparsers)``, which registers the verb and sets
``func=run`` on it, and ``run(args) -> int``. Modules import heavy libraries inside ``run`` so
that ``ocio-vp --help`` stays fast. No maths lives here: commands parse, call the library and
print.
"""

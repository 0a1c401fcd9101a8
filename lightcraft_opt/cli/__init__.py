"""The ``lightcraft`` command line, one module per command: its flags beside the handler
that reads them (simulate, optimize, closed_loop, montecarlo, calibrate); ``main`` builds
the parser from them. Units at this edge: degrees, m/s, converted to SI on the way in.

- :mod:`.main`: the parser, the entry point and its exit statuses;
- :mod:`.args`: the flags' ``type=`` converters (ranges, reasons) and the output folder;
- :mod:`.flags`: flags several commands share; :mod:`.file_kinds`: which command reads a
  file; :mod:`.progress`: progress lines of long work.
"""

from lightcraft_opt.cli.file_kinds import file_kind
from lightcraft_opt.cli.main import DESCRIPTION, build_parser, main

__all__ = ["DESCRIPTION", "build_parser", "file_kind", "main"]

"""The disk cache: what a run writes to reuse later (docs/architecture.md#rule-18).

- entries.py: a cache entry, a file and its checksum: the cache folder, keys, the
  atomic write, verification before use, removal and a warning when damaged;
- functions.py: casadi Functions on disk (Φ's chain derivatives, the NLP's surrogate);
- compiler.py: the C compiler, and the libraries it makes from casadi Functions.

The MPC's scheduled models (control/prediction_model.py) are entries too.
"""

from lightcraft_opt.compiled.cache.compiler import (
    DEFAULT_FLAGS,
    DERIVATIVE_FLAGS,
    CompilationWarning,
    CompileJob,
    casadi_link_flags,
    compile_all,
    compile_function,
    compiler_version,
    library_path,
)
from lightcraft_opt.compiled.cache.entries import (
    BuildReport,
    CacheWarning,
    EntryCheck,
    EntryStatus,
    cache_dir,
    check_entry,
    checksum_path,
    discard_entry,
    entry_file,
    load_entry,
    read_entry,
    reported_builds,
    reporter,
    source_digest,
    structure_key,
    write_entry,
)
from lightcraft_opt.compiled.cache.functions import cache_path, load_functions, save_functions

__all__ = [
    "DEFAULT_FLAGS",
    "DERIVATIVE_FLAGS",
    "BuildReport",
    "CacheWarning",
    "CompilationWarning",
    "CompileJob",
    "EntryCheck",
    "EntryStatus",
    "cache_dir",
    "cache_path",
    "casadi_link_flags",
    "check_entry",
    "checksum_path",
    "compile_all",
    "compile_function",
    "compiler_version",
    "discard_entry",
    "entry_file",
    "library_path",
    "load_entry",
    "load_functions",
    "read_entry",
    "reported_builds",
    "reporter",
    "save_functions",
    "source_digest",
    "structure_key",
    "write_entry",
]

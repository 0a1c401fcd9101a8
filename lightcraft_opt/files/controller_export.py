"""A controller's step as standalone C: source, header, Makefile, README and a replay test.

:func:`export_controller` writes a controller's two step Functions (``<name>_step(x, t,
memory) -> (u, memory_next, diagnostics, u_fallback, memory_fallback)`` and
``<name>_fallback(x, t, memory) -> (u, memory_next, diagnostics)``, control/director_step.py)
as casadi-generated C into one folder (docs/director.md#exported-c):

- ``<name>_step.c``, ``<name>_step.h``: the Functions, Ψ's pieces and the QP inside; C that
  calls HPIPM gets the options casadi leaves unset (compiled/cache/hpipm_source.py);
- ``memory0.txt``: the memory before a flight, one number a line;
- ``replay.c``: a test program that reads replay.csv (what ``lightcraft closed-loop`` wrote:
  what the controller was told and answered each pulse, files/controller_replay.py), steps the
  C controller through it, compares every input with the recorded one and, given a number of
  steps, keeps stepping through the recording that many times more and compares the process's
  peak memory after them with the one after the first pass;
- ``Makefile``: ``make`` builds ``libcontroller.a`` and ``replay`` against the HPIPM and
  BLASFEO of the casadi wheel it was exported with (``CASADI=...`` points elsewhere);
- ``README.md``: how to build, call and test it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from lightcraft_opt.compiled.cache import DERIVATIVE_FLAGS
from lightcraft_opt.compiled.cache.hpipm_source import fixed_source, uses_hpipm
from lightcraft_opt.errors import ParameterError

__all__ = ["ExportedController", "export_controller", "replay_source"]

#: Largest relative input difference the replay accepts, |u - u_rec| / max(1, |u_rec|).
REPLAY_TOLERANCE = 1e-9
#: Largest growth of the peak resident memory over the extra steps [kB].
MEMORY_GROWTH_KB = 1024


@dataclass(frozen=True)
class ExportedController:
    """The files :func:`export_controller` wrote (paths in ``folder``)."""

    folder: Path
    name: str
    source: Path
    header: Path
    memory0: Path
    replay: Path
    makefile: Path
    readme: Path


def replay_source(step: str, fallback: str, header: str) -> str:
    """replay.c for the generated Functions ``step`` and ``fallback`` declared in ``header``
    (module docstring)."""
    return (
        _REPLAY_C.replace("@STEP@", step)
        .replace("@FALLBACK@", fallback)
        .replace("@HEADER@", header)
        .replace("@TOL@", repr(REPLAY_TOLERANCE))
        .replace("@GROWTH@", str(MEMORY_GROWTH_KB))
    )


def export_controller(
    step: ca.Function,
    fallback: ca.Function,
    memory0: np.ndarray,
    folder: Path,
    *,
    name: str,
    description: str = "",
) -> ExportedController:
    """Write the C controller of ``step`` and ``fallback`` (the interpreted Functions: their
    graphs become C; a compiled, external Function has none) with the memory ``memory0``
    before a flight into ``folder`` (created), files named after ``name`` ("director")."""
    for f, what in ((step, "step"), (fallback, "fallback")):
        if f.class_name() == "External":
            raise ParameterError(what, "a compiled Function has no graph to generate C from")
    memory0 = np.asarray(memory0, dtype=float).ravel()
    if memory0.size != step.nnz_in(2):
        raise ParameterError("memory0", f"needs {step.nnz_in(2)} values, got {memory0.size}")
    folder.mkdir(parents=True, exist_ok=True)
    base = f"{name}_step"
    generator = ca.CodeGenerator(f"{base}.c", {"with_header": True})
    generator.add(step)
    generator.add(fallback)
    generator.generate(str(folder) + "/")
    source, header = folder / f"{base}.c", folder / f"{base}.h"
    text = source.read_text()
    if uses_hpipm(text):
        source.write_text(fixed_source(text))
    memory_file = folder / "memory0.txt"
    memory_file.write_text("".join(f"{v:.17g}\n" for v in memory0))
    replay = folder / "replay.c"
    replay.write_text(replay_source(step.name(), fallback.name(), header.name))
    root = Path(ca.__file__).resolve().parent
    makefile = folder / "Makefile"
    makefile.write_text(
        _MAKEFILE.replace("@CASADI@", str(root))
        .replace("@BASE@", base)
        .replace("@FLAGS@", " ".join(DERIVATIVE_FLAGS))
    )
    readme = folder / "README.md"
    readme.write_text(
        _README.replace("@NAME@", name)
        .replace("@BASE@", base)
        .replace("@STEP@", step.name())
        .replace("@FALLBACK@", fallback.name())
        .replace("@NMEM@", str(memory0.size))
        .replace("@NX@", str(step.nnz_in(0)))
        .replace("@NU@", str(step.nnz_out(0)))
        .replace("@DESCRIPTION@", description or f"The {name}'s step.")
    )
    return ExportedController(folder, name, source, header, memory_file, replay, makefile, readme)


_MAKEFILE = """# Builds the exported controller and its replay test against the casadi wheel's HPIPM
# and BLASFEO (headers in $(CASADI)/include, libraries in $(CASADI)).
CASADI ?= @CASADI@
CC ?= gcc
# -O1: the generated derivative code is long straight-line C that -O2 takes minutes on
CFLAGS ?= @FLAGS@
CPPFLAGS += -I$(CASADI)/include -I.
LDLIBS += -L$(CASADI) -lhpipm -lblasfeo -Wl,-rpath,$(CASADI) -lm

all: replay

@BASE@.o: @BASE@.c @BASE@.h
\t$(CC) $(CFLAGS) $(CPPFLAGS) -fPIC -c @BASE@.c -o $@

libcontroller.a: @BASE@.o
\tar rcs $@ $^

replay: replay.c libcontroller.a
\t$(CC) $(CFLAGS) $(CPPFLAGS) replay.c libcontroller.a $(LDLIBS) -o $@

clean:
\trm -f @BASE@.o libcontroller.a replay

.PHONY: all clean
"""

_README = """# The @NAME@ as C

@DESCRIPTION@

Exported by `lightcraft export-controller` (lightcraft_opt, docs/director.md#exported-c).

## Build

    make            # libcontroller.a and the replay test, against the casadi wheel's HPIPM
    make CASADI=/path/to/site-packages/casadi   # another copy of the wheel's libraries

## Call

`@STEP@(arg, res, iw, w, mem)` (declared in `@BASE@.h`, casadi's calling convention):

- inputs: `x` (@NX@: the measured state, lightcraft_opt's STATE layout, L and B frames, SI),
  `t` (the pulse time, s), `memory` (@NMEM@: the controller's memory; `memory0.txt` before a
  flight);
- outputs: `u` (@NU@: the plant's map input for this pulse), `memory_next` (keep it for the
  next call), `diagnostics`, then `u_fallback`, `memory_fallback` (fly these instead when the
  solve came too late for you: the previous plan's next input).

A nonzero return means the QP solver did not succeed: call
`@FALLBACK@(arg, res, iw, w, mem)` with the same inputs, which returns
(`u`, `memory_next`, `diagnostics`) without solving. Work arrays: `@STEP@_work` gives their
sizes; `@STEP@_checkout()` a memory slot. Nothing is allocated between calls except what
HPIPM allocates and frees inside each solve.

## Test

    ./replay replay.csv memory0.txt 100000

replays the pulses `lightcraft closed-loop` recorded in `replay.csv` (the controller's memory
reset at each new flight), prints the largest input difference relative to max(1, |u|) and
fails above 1e-9; then steps 100,000 more times through the recording and fails if the
process's peak memory grew by more than 1 MB.
"""

_REPLAY_C = r"""/* Replays a closed-loop recording (replay.csv) through the exported controller.
 * usage: replay replay.csv memory0.txt [extra_steps]
 * exit 0: every input within @TOL@ (relative to max(1, |u|)) and, with extra steps, the peak
 * memory grew by at most @GROWTH@ kB; 1: not; 2: bad input. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include "@HEADER@"

/* entries of a casadi sparsity pattern: {nrow, ncol, 1} is dense (casadi's compact form),
 * else {nrow, ncol, colind[ncol + 1], row[nnz]} */
static casadi_int nnz(const casadi_int* sp) {
  return sp[2] == 1 ? sp[0] * sp[1] : sp[2 + sp[1]];
}

static long peak_kb(void) {
  struct rusage r;
  getrusage(RUSAGE_SELF, &r);
  return r.ru_maxrss;
}

typedef struct {
  casadi_int nx, nu, nmem, rows;
  double *t, *x, *u;
  int *flight, *use;
} Recording;

static int read_recording(const char* path, Recording* rec) {
  FILE* f = fopen(path, "r");
  if (!f) { fprintf(stderr, "replay: cannot open %s\n", path); return 2; }
  int c;
  while ((c = fgetc(f)) != '\n' && c != EOF) {}  /* the header */
  casadi_int cap = 1024, n = 0, width = rec->nx + rec->nu;
  rec->t = malloc(cap * sizeof(double));
  rec->x = malloc(cap * rec->nx * sizeof(double));
  rec->u = malloc(cap * rec->nu * sizeof(double));
  rec->flight = malloc(cap * sizeof(int));
  rec->use = malloc(cap * sizeof(int));
  for (;;) {
    double flight, k, t, use;
    if (fscanf(f, " %lf,%lf,%lf,%lf", &flight, &k, &t, &use) != 4) break;
    if (n == cap) {
      cap *= 2;
      rec->t = realloc(rec->t, cap * sizeof(double));
      rec->x = realloc(rec->x, cap * rec->nx * sizeof(double));
      rec->u = realloc(rec->u, cap * rec->nu * sizeof(double));
      rec->flight = realloc(rec->flight, cap * sizeof(int));
      rec->use = realloc(rec->use, cap * sizeof(int));
    }
    for (casadi_int i = 0; i < width; ++i) {
      double v;
      if (fscanf(f, ",%lf", &v) != 1) {
        fprintf(stderr, "replay: row %lld has fewer than %lld values\n", (long long)n + 1,
                (long long)(4 + width));
        fclose(f);
        return 2;
      }
      if (i < rec->nx) rec->x[n * rec->nx + i] = v; else rec->u[n * rec->nu + i - rec->nx] = v;
    }
    rec->flight[n] = (int)flight;
    rec->use[n] = (int)use;
    rec->t[n] = t;
    ++n;
  }
  fclose(f);
  rec->rows = n;
  if (n == 0) { fprintf(stderr, "replay: no rows in %s\n", path); return 2; }
  return 0;
}

int main(int argc, char** argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: %s replay.csv memory0.txt [extra_steps]\n", argv[0]);
    return 2;
  }
  long extra = argc > 3 ? atol(argv[3]) : 0;
  Recording rec;
  rec.nx = nnz(@STEP@_sparsity_in(0));
  rec.nmem = nnz(@STEP@_sparsity_in(2));
  rec.nu = nnz(@STEP@_sparsity_out(0));
  casadi_int ndiag = nnz(@STEP@_sparsity_out(2));
  int status = read_recording(argv[1], &rec);
  if (status) return status;

  double* memory0 = malloc(rec.nmem * sizeof(double));
  FILE* fm = fopen(argv[2], "r");
  if (!fm) { fprintf(stderr, "replay: cannot open %s\n", argv[2]); return 2; }
  for (casadi_int i = 0; i < rec.nmem; ++i) {
    if (fscanf(fm, " %lf", &memory0[i]) != 1) {
      fprintf(stderr, "replay: %s has fewer than %lld values\n", argv[2], (long long)rec.nmem);
      return 2;
    }
  }
  fclose(fm);

  casadi_int sz_arg, sz_res, sz_iw, sz_w, a2, r2, i2, w2;
  @STEP@_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
  @FALLBACK@_work(&a2, &r2, &i2, &w2);
  if (a2 > sz_arg) sz_arg = a2;
  if (r2 > sz_res) sz_res = r2;
  if (i2 > sz_iw) sz_iw = i2;
  if (w2 > sz_w) sz_w = w2;
  const double** arg = malloc(sz_arg * sizeof(double*));
  double** res = malloc(sz_res * sizeof(double*));
  casadi_int* iw = malloc((sz_iw + 1) * sizeof(casadi_int));
  double* w = malloc((sz_w + 1) * sizeof(double));
  double* memory = malloc(rec.nmem * sizeof(double));
  double* memory_next = malloc(rec.nmem * sizeof(double));
  double* memory_late = malloc(rec.nmem * sizeof(double));
  double* u = malloc(rec.nu * sizeof(double));
  double* u_late = malloc(rec.nu * sizeof(double));
  double* diag = malloc(ndiag * sizeof(double));
  @STEP@_incref();
  @FALLBACK@_incref();
  int ms = @STEP@_checkout(), mf = @FALLBACK@_checkout();

  double worst = 0.0;
  long worst_row = -1, failures = 0, steps = 0, warm_kb = 0;
  long total = rec.rows + extra;
  for (long s = 0; s < total; ++s) {
    casadi_int r = s % rec.rows;
    if (r == 0 || rec.flight[r] != rec.flight[r - 1]) {
      memcpy(memory, memory0, rec.nmem * sizeof(double));
    }
    double t = rec.t[r];
    arg[0] = rec.x + r * rec.nx;
    arg[1] = &t;
    arg[2] = memory;
    int failed = 1;
    if (rec.use[r] != 1) {
      res[0] = u; res[1] = memory_next; res[2] = diag; res[3] = u_late; res[4] = memory_late;
      failed = @STEP@(arg, res, iw, w, ms);
      if (failed && s < rec.rows) ++failures;  /* recorded as solved, failed here */
      if (!failed && rec.use[r] == 2) {
        memcpy(u, u_late, rec.nu * sizeof(double));
        memcpy(memory_next, memory_late, rec.nmem * sizeof(double));
      }
    }
    if (failed) {
      res[0] = u; res[1] = memory_next; res[2] = diag;
      if (@FALLBACK@(arg, res, iw, w, mf)) {
        fprintf(stderr, "replay: the fallback failed\n");
        return 1;
      }
    }
    if (s < rec.rows) {
      for (casadi_int i = 0; i < rec.nu; ++i) {
        double ref = rec.u[r * rec.nu + i];
        double d = fabs(u[i] - ref) / fmax(1.0, fabs(ref));
        if (!(d <= worst)) { worst = d; worst_row = (long)r; }
      }
    }
    memcpy(memory, memory_next, rec.nmem * sizeof(double));
    ++steps;
    if (s + 1 == rec.rows) warm_kb = peak_kb();
  }
  long end_kb = peak_kb();
  @STEP@_release(ms);
  @FALLBACK@_release(mf);
  @STEP@_decref();
  @FALLBACK@_decref();
  printf("replayed %lld pulses: largest input difference %.3g (row %ld), %ld solves failed "
         "that were recorded as solved\n", (long long)rec.rows, worst, worst_row, failures);
  int ok = worst <= @TOL@ && failures == 0;
  if (extra > 0) {
    printf("memory: peak %ld kB after the recording, %ld kB after %ld steps (+%ld kB)\n",
           warm_kb, end_kb, steps, end_kb - warm_kb);
    ok = ok && end_kb - warm_kb <= @GROWTH@;
  }
  printf("%s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}
"""

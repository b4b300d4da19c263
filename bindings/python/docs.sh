#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# HTML API reference of the `kissm` Python package: bash bindings/python/docs.sh OUTDIR
#
# pdoc (pinned) runs in its own venv ($KISSM_DOCS_VENV, default ${KISSM_BUILD_DIR:-<repo>/build}/venv-docs)
# on the package's sources, with the library of a CMake build: $KISSM_LIBRARY, else
# $KISSM_BUILD_DIR/libkissm.so (tools/build.sh makes it). Fails when a public name (anything in
# kissm.__all__ or kissm.batch, and the public methods, properties and fields of their classes) has no
# docstring, and on any warning or error from pdoc.
set -euo pipefail
if (($# != 1)); then
  echo "usage: $0 OUTDIR" >&2
  exit 2
fi
out=$1
package=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$package/../.." && pwd)
build=${KISSM_BUILD_DIR:-$repo/build}
venv=${KISSM_DOCS_VENV:-$build/venv-docs}
python=${PYTHON:-python3}
library=${KISSM_LIBRARY:-$build/libkissm.so}
if [[ ! -f $library ]]; then
  echo "docs: no kissm library at $library: run tools/build.sh, or set KISSM_LIBRARY to a built libkissm.so" >&2
  exit 1
fi

if ! "$venv/bin/python" -c 'import sys' >/dev/null 2>&1; then
  rm -rf "$venv"
  mkdir -p "$(dirname "$venv")"
  "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check pdoc==16.0.0 numpy==2.4.6 cffi==2.1.1

export KISSM_LIBRARY=$library PYTHONPATH=$package/src
# Every public name documented (pdoc's own view of the package: variable docstrings included).
"$venv/bin/python" - <<'EOF'
import sys

import pdoc.doc

import kissm
import kissm.batch


def undocumented(doc: pdoc.doc.Namespace, inherited_ok: frozenset[str] = frozenset()) -> list[str]:
    missing = []
    for name, member in doc.members.items():
        if name.startswith("_") or name in inherited_ok or member.taken_from[0] == "builtins":
            continue
        if not member.docstring.strip():
            missing.append(member.qualname or name)
        if isinstance(member, pdoc.doc.Class):
            # Exception classes re-set Error's status and status_name, which Error documents.
            documented_by_error = frozenset(("status", "status_name")) if issubclass(member.obj, kissm.Error) else frozenset()
            missing += undocumented(member, documented_by_error if member.obj is not kissm.Error else frozenset())
    return missing


missing = undocumented(pdoc.doc.Module(kissm)) + undocumented(pdoc.doc.Module(kissm.batch))
if missing:
    sys.exit("docs: public names without a docstring: " + ", ".join(missing))
EOF

rm -rf "$out"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# -W error: pdoc reports problems (unresolvable annotations, broken references...) as warnings. It also
# warns that kissm.library_path equals $KISSM_LIBRARY (a library path, no secret): shown on purpose.
status=0
PDOC_DISPLAY_ENV_VARS=1 "$venv/bin/python" -W error -m pdoc --docformat google --no-include-undocumented --footer-text "kissm $(
  "$venv/bin/python" -c 'import kissm; print(kissm.__version__)')" --output-directory "$out" kissm >"$log" 2>&1 ||
  status=$?
if ((status != 0)) || [[ -s $log ]]; then
  cat "$log" >&2
  echo "docs: pdoc failed or warned (exit status $status)" >&2
  exit 1
fi
echo "docs: $out/index.html"

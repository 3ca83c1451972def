#!/usr/bin/env bash
# Rewrites the parameter tables of docs/METHODS.md from the code (canopy-bench --list-methods
# --markdown): each block between "<!-- parameters:NAME -->" and "<!-- /parameters -->".
# The test ParameterDocs.MethodsMdHoldsTheGeneratedTables fails until this is run after a
# parameter changes.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bench=${CANOPY_BENCH:-$here/build/release/bin/canopy-bench}
generated=$(mktemp)
trap 'rm -f "$generated"' EXIT
"$bench" --list-methods --markdown > "$generated"
/usr/bin/python3 - "$here/docs/METHODS.md" "$generated" <<'PY'
import re
import sys

docs_path, generated_path = sys.argv[1], sys.argv[2]
block = re.compile(r"<!-- parameters:(\S+) -->\n.*?<!-- /parameters -->", re.S)
generated = {m.group(1): m.group(0) for m in block.finditer(open(generated_path).read())}
text = open(docs_path).read()
present = {m.group(1) for m in block.finditer(text)}
text = block.sub(lambda m: generated.get(m.group(1), m.group(0)), text)
open(docs_path, "w").write(text)
missing = sorted(set(generated) - present)
if missing:
    sys.exit("docs/METHODS.md has no parameter block for: " + ", ".join(missing) +
             " (add '<!-- parameters:NAME -->' and '<!-- /parameters -->' under its section)")
PY

#!/usr/bin/env bash
# Regenerates docs/PARAMETERS.md from the code (`upd params --markdown`), so the defaults are
# written once, in the parameter structs. A test fails when the file is out of date.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
UPD="${UPD_BUILD:-$ROOT/build}/apps/upd/upd"
{
  cat <<'HEAD'
# Parameters

Every parameter of UPD-Nav, with its ini section, key, default and unit. This file is generated
from the code by `scripts/gen-docs.sh` (`upd params --markdown`); `upd params --ini` prints the
same as an ini file to start a config from.

Units are in the key names (`_m` metres, `_deg` degrees, `_s` seconds); SI units and radians
are used inside the library. In an ini file, a key that is absent keeps its default; an unknown
section or key, or a value that does not parse or breaks its rule, stops the program with a
message naming the file, section, key and value. A key with a fixed set of values (`method`,
`weighting`) takes their names; the numbers older configs hold still load. The robot configs in
`config/` set only what differs from these defaults.
HEAD
  "$UPD" params --markdown
} > "$ROOT/docs/PARAMETERS.md.tmp"
mv "$ROOT/docs/PARAMETERS.md.tmp" "$ROOT/docs/PARAMETERS.md"
echo "wrote docs/PARAMETERS.md"

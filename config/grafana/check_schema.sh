#!/usr/bin/env bash
# Checks allanscope.json against the dashboard types Grafana itself publishes (npm package
# @grafana/schema, the model its frontend loads dashboards into), with TypeScript's excess-property
# and literal-type checks: a misspelled key, a key Grafana does not know, or a value of the wrong
# kind fails. This complements tests/sink/grafana.rs (our own reading of the model) and needs Node
# and npm with the npm registry, which CI's machine does not have; run it by hand:
#     bash config/grafana/check_schema.sh
# The import's `__inputs`, `__requires` and `__elements` are outside the dashboard model (Grafana's
# export adds them) and are allowed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
schema_version="${GRAFANA_SCHEMA_VERSION:-13.2.3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund --loglevel=error "@grafana/schema@$schema_version" typescript@7 >/dev/null
node -e '
const fs = require("fs");
const d = JSON.parse(fs.readFileSync(process.argv[1], "utf8"));
fs.writeFileSync("check.ts",
  "import type { Dashboard } from \"@grafana/schema\";\n" +
  "type Exported = Dashboard & { __inputs?: unknown; __requires?: unknown; __elements?: unknown };\n" +
  "export const dashboard = " + JSON.stringify(d, null, 1) + " satisfies Exported;\n");
' "$here/allanscope.json"
npx tsc --noEmit --strict --skipLibCheck --module nodenext --moduleResolution nodenext --target es2020 check.ts
echo "allanscope.json matches @grafana/schema $schema_version's Dashboard type"

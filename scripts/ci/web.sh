#!/usr/bin/env bash
# Web view tests on a fresh machine: installs Debian's chromium and node (if missing) and the
# pinned playwright-core, builds armhil, runs the page unit tests (node --test) and the
# browser tests (headless Chromium). Screenshots land in $ARMHIL_SCREENSHOTS (default out/web)
# for CI to archive; with --docs they are also copied to docs/img/.
set -euo pipefail

cd "$(dirname "$0")/../.."
ROOT=$PWD

need_apt=()
[ -x /usr/bin/chromium ] || need_apt+=(chromium)
command -v node >/dev/null || need_apt+=(nodejs)
command -v npm >/dev/null || need_apt+=(npm)
if [ ${#need_apt[@]} -gt 0 ]; then
    echo "web.sh: installing ${need_apt[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${need_apt[@]}"
fi

# The page scripts' own tests need nothing installed.
node --test web/tests/unit/*.test.js

(cd web/tests && npm ci --no-audit --no-fund --loglevel=error)

cargo build --bin armhil
TARGET_DIR=$(cargo metadata --format-version 1 --no-deps | node -e 'let s="";process.stdin.on("data",d=>s+=d).on("end",()=>console.log(JSON.parse(s).target_directory))')
export ARMHIL_BIN="$TARGET_DIR/debug/armhil"
export ARMHIL_SCREENSHOTS="${ARMHIL_SCREENSHOTS:-out/web}"
export CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"

node --test web/tests/browser/*.test.js

if [ "${1:-}" = "--docs" ]; then
    mkdir -p docs/img
    cp "$ARMHIL_SCREENSHOTS"/{live,live_fault,live_robstride,live_realman,report,report_plots}.png docs/img/
    echo "web.sh: screenshots copied to docs/img/"
fi
echo "web.sh: screenshots in $ROOT/$ARMHIL_SCREENSHOTS"

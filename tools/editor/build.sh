#!/usr/bin/env bash
# Rebuilds crates/luster/src/watch/editor.js, the watch page's shader editor:
# CodeMirror 6 at the exact versions of package-lock.json, bundled and
# minified by esbuild. Needs node and npm (CI does not: the bundle is
# committed). CodeMirror is MIT licensed; the bundle starts with its notice.
set -euo pipefail
cd "$(dirname "$0")"
npm ci --no-audit --no-fund --silent
out=../../crates/luster/src/watch/editor.js
notice="/*! luster watch editor: CodeMirror 6 (https://codemirror.net), MIT License, Copyright (C) 2018-2021 by Marijn Haverbeke <marijn@haverbeke.berlin> and others; bundled by tools/editor/build.sh */"
./node_modules/.bin/esbuild entry.js --bundle --minify --format=iife --global-name=LusterEditor \
    --legal-comments=none --target=es2020 --charset=utf8 "--banner:js=$notice" --outfile="$out"
echo "$out: $(wc -c <"$out") bytes"

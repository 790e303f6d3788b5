// Tokenise files with the extension's TextMate grammar, as VS Code does (vscode-textmate on
// the Oniguruma regular expressions of vscode-oniguruma), for tests/unit/editors/test_grammar.py.
//   node test/tokenize.js FILE...   ->  stdout: one JSON document
// {"scopes": [scope list, ...], "files": {FILE: [[line's tokens: [start, end, scope index], ...], ...]}}
// Offsets are UTF-16 units within the line; lines are split at \r\n and \n.
"use strict";

const fs = require("fs");
const path = require("path");
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");

const root = path.resolve(__dirname, "..");
const grammarPath = path.join(root, "syntaxes", "sleec.tmLanguage.json");

async function main(files) {
  const wasm = fs.readFileSync(path.join(path.dirname(require.resolve("vscode-oniguruma")), "onig.wasm"));
  await oniguruma.loadWASM(wasm.buffer.slice(wasm.byteOffset, wasm.byteOffset + wasm.byteLength));
  const registry = new vsctm.Registry({
    onigLib: Promise.resolve({
      createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
      createOnigString: (s) => new oniguruma.OnigString(s),
    }),
    loadGrammar: async (scopeName) =>
      scopeName === "source.sleec"
        ? vsctm.parseRawGrammar(fs.readFileSync(grammarPath, "utf8"), grammarPath)
        : null,
  });
  const grammar = await registry.loadGrammar("source.sleec");
  const scopes = [];
  const index = new Map();
  const out = {};
  for (const file of files) {
    const text = fs.readFileSync(file, "utf8");
    let stack = vsctm.INITIAL;
    const lines = [];
    for (const line of text.split(/\r?\n/)) {
      const r = grammar.tokenizeLine(line, stack);
      lines.push(
        r.tokens.map((t) => {
          const key = t.scopes.join(" ");
          if (!index.has(key)) {
            index.set(key, scopes.length);
            scopes.push(t.scopes);
          }
          return [t.startIndex, Math.min(t.endIndex, line.length), index.get(key)];
        }),
      );
      stack = r.ruleStack;
    }
    out[file] = lines;
  }
  process.stdout.write(JSON.stringify({ scopes, files: out }));
}

main(process.argv.slice(2)).catch((e) => {
  console.error(e);
  process.exit(1);
});

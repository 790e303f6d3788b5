// The cosleec VS Code extension: SLEEC highlighting (syntaxes/sleec.tmLanguage.json) and
// the cosleec language server, started as `cosleec lsp` over stdio (docs/editors.md).
"use strict";

const vscode = require("vscode");
const { LanguageClient, TransportKind } = require("vscode-languageclient/node");

let client;

// the settings the server reads from initializationOptions (cosleec.lsp.Settings)
function options(config) {
  return {
    dialect: config.get("dialect"),
    lint: config.get("lint"),
    strictPrecedence: config.get("strictPrecedence"),
    legosCompat: config.get("legosCompat"),
    semantics: config.get("semantics"),
    formatWidth: config.get("formatWidth"),
    analysis: config.get("analyseOnSave"),
    analysisTimeout: config.get("analysisTimeout"),
  };
}

async function start() {
  const config = vscode.workspace.getConfiguration("cosleec");
  const server = {
    command: config.get("path") || "cosleec",
    args: ["lsp"],
    transport: TransportKind.stdio,
  };
  client = new LanguageClient(
    "cosleec",
    "cosleec",
    { run: server, debug: server },
    {
      documentSelector: [
        { scheme: "file", language: "sleec" },
        { scheme: "untitled", language: "sleec" },
      ],
      initializationOptions: options(config),
    },
  );
  await client.start();
}

async function activate(context) {
  // the server reads its settings when it starts: a change of them restarts it
  context.subscriptions.push(
    vscode.workspace.onDidChangeConfiguration(async (event) => {
      if (event.affectsConfiguration("cosleec")) {
        await deactivate();
        await start();
      }
    }),
  );
  await start();
}

async function deactivate() {
  if (client) {
    const running = client;
    client = undefined;
    await running.stop();
  }
}

module.exports = { activate, deactivate };

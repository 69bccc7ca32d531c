// Cargo runner for wasm32-wasip1 test binaries (CARGO_TARGET_WASM32_WASIP1_RUNNER):
//   node .ci/wasi-run.mjs target/wasm32-wasip1/debug/deps/lanes-*.wasm [test args...]
// Runs the module under node's built-in WASI preview 1 with the environment passed through and
// the working directory (the package root, where cargo starts test binaries) preopened as "/"
// (the guest's working directory), as "." and under its own absolute path, so that proptest
// finds tests/*.rs from `file!()` and reads its *.proptest-regressions files. Exits with the
// module's exit code; a trap (a panic under panic=abort, a stack overflow) exits 101 like a
// failed test.
import { readFile } from "node:fs/promises";
import { WASI } from "node:wasi";
import process from "node:process";

const [wasmPath, ...args] = process.argv.slice(2);
if (!wasmPath) {
  console.error("usage: node wasi-run.mjs MODULE.wasm [ARGS...]");
  process.exit(2);
}
const cwd = process.cwd();
const wasi = new WASI({
  version: "preview1",
  args: [wasmPath, ...args],
  env: process.env,
  preopens: { "/": cwd, ".": cwd, [cwd]: cwd },
  returnOnExit: true,
});
try {
  const module = await WebAssembly.compile(await readFile(wasmPath));
  const instance = await WebAssembly.instantiate(module, wasi.getImportObject());
  process.exitCode = wasi.start(instance);
} catch (e) {
  console.error(`wasi-run: ${wasmPath}: ${e}`);
  process.exitCode = 101;
}

// `chopperscape web` serves the built page on 127.0.0.1, and the page runs from it.
import assert from "node:assert/strict";
import { execFileSync, spawn } from "node:child_process";
import { join } from "node:path";
import { once } from "node:events";
import { test } from "node:test";
import { DIST, launchChromium, openPage, ROOT } from "./harness.mjs";

test("chopperscape web serves the page on loopback and prints its address", async () => {
  execFileSync("cargo", ["build", "--quiet", "-p", "chopperscape-cli"], { cwd: ROOT, stdio: "inherit" });
  const bin = join(process.env.CARGO_TARGET_DIR ?? join(ROOT, "target"), "debug", "chopperscape");
  const server = spawn(bin, ["web", "--port", "0", "--dir", DIST], { stdio: ["ignore", "pipe", "inherit"] });
  const browser = await launchChromium();
  try {
    let printed = "";
    const url = await new Promise((ok, fail) => {
      server.stdout.on("data", (chunk) => {
        printed += chunk;
        const m = printed.match(/http:\/\/[^\s]+\//);
        if (m) ok(m[0]);
      });
      server.on("exit", (code) => fail(new Error(`chopperscape web exited with ${code}: ${printed}`)));
    });
    assert.match(url, /^http:\/\/127\.0\.0\.1:\d+\/$/);
    const { page, errors, close } = await openPage(browser, url);
    const s = await page.evaluate(() => window.chopperscape.stepN([3, 3, 3]));
    assert.equal(s.steps >= 3, true);
    assert.deepEqual(errors, []);
    await close();
  } finally {
    await browser.close();
    server.kill();
    if (server.exitCode === null) await once(server, "exit");
  }
});

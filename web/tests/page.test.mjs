// Browser tests of the ChopperScape page in headless Chromium.
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import { join } from "node:path";
import { test } from "node:test";
import { firstDifference, HEIGHT, nativeFrame, openPage, ROOT, useServedPage, WIDTH } from "./harness.mjs";

const env = useServedPage();

async function withPage(fn) {
  const session = await openPage(env.browser, env.server.url);
  try {
    await fn(session.page, session.errors);
  } finally {
    await session.close();
  }
}

const state = (page) => page.evaluate(() => window.chopperscape.state());
const frame = async (page, which = "frameBytes") =>
  Buffer.from(await page.evaluate((w) => window.chopperscape[w](), which), "base64");

test("page loads with no console errors and the canvas shows the chopper", async () => {
  await withPage(async (page, errors) => {
    await page.evaluate(() => window.chopperscape.setPaused(true));
    const s = await state(page);
    const rgb = await frame(page);
    assert.equal(rgb.length, WIDTH * HEIGHT * 3);
    let inked = 0;
    for (let y = s.y; y < s.y + 64; y++) {
      for (let x = s.x; x < s.x + 64; x++) {
        const i = (y * WIDTH + x) * 3;
        if (rgb[i] !== 255 || rgb[i + 1] !== 255 || rgb[i + 2] !== 255) inked++;
      }
    }
    assert.ok(inked > 200, `only ${inked} non-white pixels in the chopper's 64 × 64 box at (${s.x}, ${s.y})`);
    assert.deepEqual(errors, []);
  });
});

test("holding the up arrow moves the chopper up, and the last key pressed wins", async () => {
  await withPage(async (page, errors) => {
    await page.evaluate(() => window.chopperscape.newGame(3));
    const start = await state(page);
    await page.keyboard.down("ArrowUp");
    await page.waitForFunction((y0) => window.chopperscape.state().y <= y0 - 15, start.y);
    const up = await state(page);
    assert.equal(up.x, start.x, "up does not move the chopper sideways");
    await page.keyboard.down("KeyD"); // pressed while Up is still held: Right wins
    await page.waitForFunction((x0) => window.chopperscape.state().x >= x0 + 15, up.x);
    await page.keyboard.up("KeyD");
    await page.keyboard.up("ArrowUp");
    const right = await state(page);
    assert.ok(right.x > up.x, `x ${up.x} -> ${right.x}`);
    assert.deepEqual(errors, []);
  });
});

test("the score grows while the game runs", async () => {
  await withPage(async (page) => {
    const start = await state(page);
    await page.waitForFunction((s0) => window.chopperscape.state().steps >= s0 + 20, start.steps);
    const later = await state(page);
    assert.ok(later.score > start.score, `score ${start.score} -> ${later.score}`);
    assert.ok(later.fuel < start.fuel, `fuel ${start.fuel} -> ${later.fuel}`);
  });
});

test("watch the heuristic flies on its own", async () => {
  await withPage(async (page, errors) => {
    await page.evaluate(() => window.chopperscape.newGame(4));
    const start = await state(page);
    await page.click("#heuristic");
    assert.equal(await page.getAttribute("#heuristic", "aria-pressed"), "true");
    // The heuristic heads home to x ≈ 150 from the spawn at x < 80, with no key pressed.
    await page.waitForFunction((x0) => window.chopperscape.state().x >= x0 + 30, start.x);
    const s = await state(page);
    assert.ok(s.heuristic && s.steps > 6, JSON.stringify(s));
    assert.match(await page.textContent("#status"), /heuristic is flying/);
    assert.deepEqual(errors, []);
  });
});

test("the browser frame equals the native frame for a fixed seed and actions", async () => {
  const options = { lives: 3, alien_prob: 0.05 };
  const actions = Array.from({ length: 180 }, (_, i) => [0, 0, 3, 3, 4, 2, 2, 1][i % 8]);
  await withPage(async (page, errors) => {
    const s = await page.evaluate(
      ([opts, acts]) => {
        window.chopperscape.setPaused(true);
        const err = window.chopperscape.newGame(5, opts);
        if (err) throw new Error(err);
        return window.chopperscape.stepN(acts);
      },
      [options, actions],
    );
    assert.ok(s.steps > 0);
    const expected = nativeFrame(5, actions, options);
    assert.equal(expected.length, WIDTH * HEIGHT * 3);
    assert.equal(firstDifference(await frame(page, "wasmFrameBytes"), expected), null, "WebAssembly memory frame");
    assert.equal(firstDifference(await frame(page, "frameBytes"), expected), null, "canvas frame");
    // A frame that shows more than the chopper: the run met birds, tanks or aliens.
    const white = expected.reduce((n, b) => n + (b === 255), 0);
    assert.ok(white < expected.length - 64 * 64 * 3, "the frame shows entities besides the chopper");
    assert.deepEqual(errors, []);
  });
});

test("a mode fixes the rules as --mode does: the menu lists the core's modes, locks the rules, plays the same game", async () => {
  // docs/SPEC.md, "Difficulty modes": full-v0 is these options given one by one.
  const fullV0 = { frame_skip: 4, sticky_prob: 0.25, lives: 3, alien_prob: 0.005, bird_fuel_collision: "destroy" };
  const actions = Array.from({ length: 90 }, (_, i) => [3, 3, 0, 4, 2, 1][i % 6]);
  await withPage(async (page, errors) => {
    const listed = await page.evaluate(() => [...document.querySelectorAll("#mode option")].map((o) => o.value));
    assert.deepEqual(listed, ["", "v0", "sticky-v0", "full-v0"]);
    const s = await page.evaluate((acts) => {
      window.chopperscape.setPaused(true);
      const err = window.chopperscape.newGame(5, { mode: "full-v0" });
      if (err) throw new Error(err);
      return window.chopperscape.stepN(acts);
    }, actions);
    assert.ok(s.steps > 0);
    assert.equal(await page.inputValue("#lives"), "3");
    assert.equal(await page.inputValue("#alien_prob"), "0.005");
    assert.equal(await page.isDisabled("#lives"), true);
    const expected = nativeFrame(5, actions, fullV0);
    assert.equal(firstDifference(await frame(page, "frameBytes"), expected), null, "the mode's game is its options'");
    // "custom" hands the rules back to the form.
    await page.selectOption("#mode", "");
    assert.equal(await page.isDisabled("#lives"), false);
    assert.deepEqual(errors, []);
  });
});

test("an option out of range is refused with its name and changes nothing", async () => {
  await withPage(async (page) => {
    await page.evaluate(() => window.chopperscape.setPaused(true));
    const before = await state(page);
    const err = await page.evaluate(() => window.chopperscape.newGame(1, { lives: 0 }));
    assert.match(err, /lives/);
    assert.match(err, /1\.\.=1000/);
    assert.equal(await page.isVisible("#error"), true);
    assert.match(await page.textContent("#error"), /lives/);
    assert.deepEqual(await state(page), before);
    const seedErr = await page.evaluate(() => window.chopperscape.newGame("-3"));
    assert.match(seedErr, /seed/);
  });
});

test("P pauses, the end of an episode says why, and R starts a new game with the next seed", async () => {
  await withPage(async (page) => {
    await page.evaluate(() => window.chopperscape.newGame(41));
    await page.focus("#screen");
    await page.keyboard.press("KeyP");
    assert.equal((await state(page)).paused, true);
    assert.equal(await page.isVisible("#paused"), true);
    const paused = await state(page);
    await page.waitForTimeout(300);
    assert.equal((await state(page)).steps, paused.steps, "no steps while paused");

    // Hovering still: the episode ends by a bird, or by fuel once no tank happens to rise through the chopper.
    const end = await page.evaluate(() => {
      let s = window.chopperscape.state();
      while (!s.over && s.steps < 10000) s = window.chopperscape.stepN(Array(500).fill(4));
      return s;
    });
    assert.equal(end.over, true);
    assert.ok(end.cause === "bird" || end.cause === "fuel", end.cause);
    assert.equal(await page.isVisible("#message"), true);
    const title = await page.textContent("#message-title");
    assert.equal(title, end.cause === "fuel" ? "Out of fuel" : "Hit by a bird");
    assert.match(await page.textContent("#message-detail"), new RegExp(`Return ${end.score} after ${end.steps} steps`));

    await page.keyboard.press("KeyR");
    const fresh = await state(page);
    assert.equal(fresh.over, false);
    assert.equal(fresh.steps, 0);
    assert.equal(fresh.seed, "42");
    assert.equal(await page.inputValue("#seed"), "42");
    assert.equal(await page.isVisible("#message"), false);
  });
});

test("watch: trained agent plays the command line's episode for the same seed", async () => {
  execFileSync("cargo", ["build", "--quiet", "-p", "chopperscape-cli"], { cwd: ROOT, stdio: "inherit" });
  const bin = join(process.env.CARGO_TARGET_DIR ?? join(ROOT, "target"), "debug", "chopperscape");
  const model = join(ROOT, "models", "ppo-features.onnx");
  // Aliens make the episode end early, at a step that depends on every action the policy picked.
  const args = ["demo", "--policy", model, "--seed", "3", "--aliens", "0.05", "--json"];
  const native = JSON.parse(execFileSync(bin, args, { stdio: ["ignore", "pipe", "ignore"] }).toString());
  await withPage(async (page, errors) => {
    await page.evaluate(() => window.chopperscape.setPaused(true));
    assert.equal(await page.evaluate(() => window.chopperscape.newGame(3, { alien_prob: 0.05 })), null);
    assert.equal(await page.evaluate(() => window.chopperscape.setAgent(true)), null);
    assert.equal(await page.getAttribute("#agent", "aria-pressed"), "true");
    const s = await page.evaluate(() => window.chopperscape.playToEnd());
    assert.equal(s.agent, true);
    assert.deepEqual([s.steps, s.score, s.cause], [native.steps, native.return, native.cause]);
    assert.match(await page.textContent("#status"), /trained agent is flying/);
    assert.deepEqual(errors, []);
  });
});

test("watch: the pixel agent plays the command line's episode for the same seed", async () => {
  execFileSync("cargo", ["build", "--quiet", "-p", "chopperscape-cli"], { cwd: ROOT, stdio: "inherit" });
  const bin = join(process.env.CARGO_TARGET_DIR ?? join(ROOT, "target"), "debug", "chopperscape");
  const model = join(ROOT, "models", "ppo-pixels.onnx");
  const args = ["demo", "--policy", model, "--seed", "3", "--aliens", "0.05", "--json"];
  const native = JSON.parse(execFileSync(bin, args, { stdio: ["ignore", "pipe", "ignore"] }).toString());
  await withPage(async (page, errors) => {
    await page.evaluate(() => window.chopperscape.setPaused(true));
    assert.equal(await page.evaluate(() => window.chopperscape.newGame(3, { alien_prob: 0.05 })), null);
    await page.selectOption("#agent-model", "pixels");
    assert.equal(await page.evaluate(() => window.chopperscape.setAgent(true)), null);
    const s = await page.evaluate(() => window.chopperscape.playToEnd());
    assert.equal(s.agent, true);
    assert.deepEqual([s.steps, s.score, s.cause], [native.steps, native.return, native.cause]);
    // Back to the features agent: a new game with the same seed, flown by the MLP.
    await page.selectOption("#agent-model", "features");
    assert.equal(await page.evaluate(() => window.chopperscape.setAgent(true)), null);
    assert.equal((await state(page)).agent, true);
    assert.deepEqual(errors, []);
  });
});

test("a missing or bad model file says so on the page", async () => {
  await withPage(async (page) => {
    await page.evaluate(() => window.chopperscape.setPaused(true));
    const before = await state(page);
    await page.route("**/models/ppo-features.onnx", (route) => route.fulfill({ status: 404, body: "" }));
    let err = await page.evaluate(() => window.chopperscape.setAgent(true));
    assert.match(err, /trained agent could not be loaded.*404/);
    assert.equal(await page.isVisible("#error"), true);
    assert.match(await page.textContent("#error"), /could not be loaded/);
    await page.unroute("**/models/ppo-features.onnx");
    await page.route("**/models/ppo-features.onnx", (route) => route.fulfill({ status: 200, body: "not a model" }));
    err = await page.evaluate(() => window.chopperscape.setAgent(true));
    assert.match(err, /not a ChopperScape policy/);
    const after = await state(page);
    assert.equal(after.agent, false);
    assert.deepEqual({ ...after, agent: undefined }, { ...before, agent: undefined });
  });
});

// The page's Train control in headless Chromium: the Rust learner in its Web Worker learns a few thousand
// decisions (a small batch, `?train_envs=8&train_steps=64`), the curve grows, the greedy policy is evaluated on the
// held-out episodes every 3 updates (`&train_eval_every=3`) beside the heuristic's on the same episodes, the flown
// policy is replaced by the newer one, the page's own loop keeps running meanwhile, and Stop stops it.
import assert from "node:assert/strict";
import { test } from "node:test";
import { openPage, useServedPage } from "./harness.mjs";

const env = useServedPage();

test("Train learns in a worker: the curve grows, the flown policy updates, the page does not block", async () => {
  const { page, errors, close } = await openPage(env.browser, `${env.server.url}?train_envs=8&train_steps=64&train_eval_every=3`);
  try {
    await page.waitForFunction(() => window.chopperscapeTrain !== undefined);
    // Frames the page draws while the worker learns: a blocked main thread would draw none.
    await page.evaluate(() => {
      window.framesDrawn = 0;
      const tick = () => {
        window.framesDrawn++;
        requestAnimationFrame(tick);
      };
      requestAnimationFrame(tick);
    });
    await page.click("#train");
    // Six updates of 512 decisions: 3,072 decisions.
    // (Each evaluation is posted just after its update's row: wait for both.)
    const six = () => window.chopperscapeTrain.rows.length >= 6 && window.chopperscapeTrain.evals.length >= 2;
    await page.waitForFunction(six, null, { timeout: 240_000 });
    const s = await page.evaluate(() => {
      const t = window.chopperscapeTrain;
      return {
        rows: t.rows.map((r) => r.envSteps),
        evals: t.evals,
        heuristic: t.heuristic,
        policies: t.policies,
        flown: t.flownPolicy,
        dps: t.decisionsPerSec,
      };
    });
    assert.ok(s.rows.every((v, i) => i === 0 || v > s.rows[i - 1]), `decisions grow: ${s.rows}`);
    assert.ok(s.rows.at(-1) >= 3000, `${s.rows.at(-1)} decisions`);
    assert.ok(s.policies >= 6 && s.flown >= 1, `policies ${s.policies}, flown ${s.flown}`);
    assert.ok(s.dps > 0);
    // Evaluated after updates 3 and 6, at their decisions; the heuristic on the same 20 held-out episodes is far
    // above a policy of 3,000 decisions.
    assert.ok(s.evals.length >= 2, `evaluations: ${JSON.stringify(s.evals)}`);
    assert.deepEqual(s.evals.slice(0, 2).map((e) => e.envSteps), [s.rows[2], s.rows[5]]);
    assert.ok(s.evals.every((e) => e.mean > 0) && s.heuristic > 2 * s.evals[0].mean, JSON.stringify(s));
    // The page kept drawing while the worker learned (nothing blocked its main thread).
    const frames = await page.evaluate(() => window.framesDrawn);
    assert.ok(frames > 30, `${frames} frames drawn while learning`);
    // The curve was drawn: the canvas holds the curve's red.
    const red = await page.evaluate(() => {
      const c = document.getElementById("curve");
      const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] > 150 && d[i + 1] < 100 && d[i + 2] < 100) n++;
      return n;
    });
    assert.ok(red > 20, `${red} red pixels in the curve`);
    await page.click("#train"); // Stop
    // The worker answers the Stop; rows it learned before reading it may still arrive until then, none after.
    await page.waitForFunction(() => window.chopperscapeTrain.stoppedRows !== null, null, { timeout: 60_000 });
    const stopped = await page.evaluate(() => window.chopperscapeTrain.stoppedRows);
    await page.waitForTimeout(3000);
    const later = await page.evaluate(() => window.chopperscapeTrain.rows.length);
    assert.equal(later, stopped, `still learning after Stop: ${stopped} → ${later}`);
    assert.equal(await page.textContent("#train"), "Resume");
    assert.deepEqual(errors, []);
  } finally {
    await close();
  }
});

// The page's learner, measured (a benchmark, not a test: docs/rust-learner.md): headless Chromium opens the built
// page (web/dist), clicks Train with the preset's full batch, and prints one CSV row every 10 s (decisions, the
// training return of the last 100 episodes, the greedy policy's latest held-out evaluation and the heuristic's on
// the same 20 episodes) until that evaluation passes the heuristic's, the run ends, or SECONDS pass:
//   node web/tests/train-speed.mjs [SECONDS=300] > train-speed.csv
import { openPage, serveDist, launchChromium } from "./harness.mjs";

const limit = Number(process.argv[2] ?? 300);
const server = await serveDist();
const browser = await launchChromium();
const { page, errors, close } = await openPage(browser, server.url);
try {
  await page.waitForFunction(() => window.chopperscapeTrain !== undefined);
  await page.click("#train");
  const start = Date.now();
  console.log("seconds,decisions,mean_return,held_out,heuristic,decisions_per_s,passed_at_s");
  for (;;) {
    await page.waitForTimeout(10_000);
    const s = await page.evaluate(() => {
      const t = window.chopperscapeTrain;
      const last = t.rows.at(-1);
      const held = t.evals.at(-1)?.mean ?? null;
      const common = { held, heuristic: t.heuristic, dps: t.decisionsPerSec, passed: t.passedAt, running: t.running };
      return { steps: last?.envSteps ?? 0, ret: last?.meanReturn ?? null, ...common };
    });
    const secs = (Date.now() - start) / 1000;
    const num = (v) => (v === null ? "" : v.toFixed(1));
    const cols = [secs.toFixed(0), s.steps, num(s.ret), num(s.held), num(s.heuristic), Math.round(s.dps), num(s.passed)];
    console.log(cols.join(","));
    if (s.passed !== null || !s.running || secs >= limit) break;
  }
  if (errors.length) console.error(errors.join("\n"));
} finally {
  await close();
  await browser.close();
  await server.close();
}

// The page's learner, measured (a benchmark, not a test: docs/rust-learner.md): headless Chromium opens the built
// page (web/dist), clicks Train with the preset's full batch, and prints one CSV row every 10 s until the training
// return (the last 100 episodes of the stochastic policy) passes the heuristic's 10,616 or SECONDS pass:
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
  console.log("seconds,decisions,mean_return,decisions_per_s,passed_at_s");
  for (;;) {
    await page.waitForTimeout(10_000);
    const s = await page.evaluate(() => {
      const t = window.chopperscapeTrain;
      const last = t.rows.at(-1);
      return { steps: last?.envSteps ?? 0, ret: last?.meanReturn ?? null, dps: t.decisionsPerSec, passed: t.passedAt };
    });
    const secs = (Date.now() - start) / 1000;
    const ret = s.ret === null ? "" : s.ret.toFixed(1);
    console.log(`${secs.toFixed(0)},${s.steps},${ret},${Math.round(s.dps)},${s.passed?.toFixed(1) ?? ""}`);
    if (s.passed !== null || secs >= limit) break;
  }
  if (errors.length) console.error(errors.join("\n"));
} finally {
  await close();
  await browser.close();
  await server.close();
}

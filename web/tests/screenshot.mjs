// Regenerates docs/screenshot.png: the page mid-game, the heuristic policy flying among birds and aliens.
// Deterministic: the page's clock is faked, so the loop runs 10 s of game time (about 300 steps).
//   bash scripts/build-web.sh && node web/tests/screenshot.mjs
import { renameSync } from "node:fs";
import { join } from "node:path";
import { launchChromium, openPage, ROOT, serveDist } from "./harness.mjs";

const out = join(ROOT, "docs", "screenshot.png");
const server = await serveDist();
const browser = await launchChromium();
try {
  const { page, errors } = await openPage(browser, server.url, { clock: true });
  await page.evaluate(() => window.chopperscape.newGame(22, { lives: 3, alien_prob: 0.01 }));
  await page.click("#heuristic");
  await page.mouse.move(0, 0);
  await page.clock.runFor(10000);
  if (errors.length) throw new Error(`console errors: ${errors.join("; ")}`);
  const tmp = `${out}.tmp.png`;
  await page.locator("main").screenshot({ path: tmp });
  renameSync(tmp, out);
  console.log(`wrote ${out}: ${JSON.stringify(await page.evaluate(() => window.chopperscape.state()))}`);
} finally {
  await browser.close();
  await server.close();
}

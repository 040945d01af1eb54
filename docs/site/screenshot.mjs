// Regenerates docs/site/screenshot-env-page.png: the built environment page (docs/site/_build/html/environment.html)
// in headless Debian Chromium, driven by web/tests' playwright-core, at a desktop width, top of the page.
//   (cd web/tests && npm ci) && node docs/site/screenshot.mjs       (after the site is built)
import { createRequire } from "node:module";
import { existsSync, renameSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const HERE = dirname(fileURLToPath(import.meta.url));
const ROOT = join(HERE, "..", "..");
const { chromium } = createRequire(join(ROOT, "web", "tests", "package.json"))("playwright-core");
const page_file = join(HERE, "_build", "html", "environment.html");
if (!existsSync(page_file)) throw new Error(`${page_file} is not built: run scripts/test-dist.sh first`);
const out = join(HERE, "screenshot-env-page.png");

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 1100 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  page.on("requestfailed", (r) => errors.push(`failed: ${r.url()}`));
  await page.goto(pathToFileURL(page_file).href, { waitUntil: "load" });
  // Wait until every image is decoded (the GIF shows whichever frame it reached: the picture differs run to run).
  await page.evaluate(() => Promise.all([...document.images].map((i) => i.decode().catch(() => {}))));
  if (errors.length) throw new Error(errors.join("; "));
  const tmp = `${out}.tmp.png`;
  await page.screenshot({ path: tmp });
  renameSync(tmp, out);
  console.log(`wrote ${out}`);
} finally {
  await browser.close();
}

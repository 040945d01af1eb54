// Shared pieces of the browser tests: a static server for web/dist, headless Debian Chromium, and the
// native reference frame from the Rust example.
import { after, before } from "node:test";
import { execFileSync } from "node:child_process";
import { createReadStream, existsSync, statSync } from "node:fs";
import { createServer } from "node:http";
import { extname, join, normalize, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";

export const ROOT = resolve(fileURLToPath(import.meta.url), "../../..");
export const DIST = join(ROOT, "web", "dist");
export const WIDTH = 800;
export const HEIGHT = 600;

const TYPES = {
  ".html": "text/html; charset=utf-8",
  ".js": "text/javascript; charset=utf-8",
  ".css": "text/css; charset=utf-8",
  ".wasm": "application/wasm",
};

// Serves web/dist on 127.0.0.1 at a free port. Resolves to { url, close }.
/** The page served from `web/dist` and one headless Chromium for a test file: registers `before`/`after` hooks that
 * start and close both, and returns an object whose `server` and `browser` are set once they run. */
export function useServedPage() {
  const env = { server: undefined, browser: undefined };
  before(async () => {
    env.server = await serveDist();
    env.browser = await launchChromium();
  });
  after(async () => {
    await env.browser?.close();
    await env.server?.close();
  });
  return env;
}

export async function serveDist() {
  if (!existsSync(join(DIST, "index.html"))) {
    throw new Error(`${DIST} is not built: run scripts/build-web.sh first`);
  }
  const server = createServer((req, res) => {
    const path = normalize(decodeURIComponent(new URL(req.url, "http://x").pathname));
    let file = join(DIST, path);
    if (!file.startsWith(DIST)) {
      res.writeHead(403).end();
      return;
    }
    if (existsSync(file) && statSync(file).isDirectory()) file = join(file, "index.html");
    if (!existsSync(file)) {
      res.writeHead(404).end();
      return;
    }
    res.writeHead(200, { "content-type": TYPES[extname(file)] ?? "application/octet-stream" });
    createReadStream(file).pipe(res);
  });
  await new Promise((ok) => server.listen(0, "127.0.0.1", ok));
  return { url: `http://127.0.0.1:${server.address().port}/`, close: () => new Promise((ok) => server.close(ok)) };
}

export function launchChromium() {
  return chromium.launch({
    executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
    args: [
      "--headless",
      "--no-sandbox",
      "--disable-gpu",
      "--disable-quic",
      "--no-first-run",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
    ],
  });
}

// Opens the page in a fresh context; collects console errors and uncaught exceptions into `errors`.
// With `clock`, the page's time (and so its 30-steps-per-second loop) only moves by `page.clock.runFor`.
export async function openPage(browser, url, { clock = false } = {}) {
  const context = await browser.newContext({ viewport: { width: 880, height: 900 } });
  const page = await context.newPage();
  if (clock) {
    await page.clock.install({ time: 0 });
    await page.clock.pauseAt(1000);
  }
  const errors = [];
  page.on("console", (msg) => {
    if (msg.type() === "error") errors.push(msg.text());
  });
  page.on("pageerror", (err) => errors.push(String(err)));
  await page.goto(url);
  await page.waitForFunction(() => window.chopperscape?.ready === true);
  return { page, errors, close: () => context.close() };
}

// The native frame (RGB, 600 × 800 × 3) for a seed, actions and options, from the core directly.
export function nativeFrame(seed, actions, options = {}) {
  const args = ["run", "--quiet", "-p", "chopperscape-web", "--example", "frame", "--"];
  args.push("--seed", String(seed), "--actions", actions.join(","));
  for (const [name, value] of Object.entries(options)) args.push("--option", `${name}=${value}`);
  return execFileSync("cargo", args, { cwd: ROOT, maxBuffer: 16 << 20, stdio: ["ignore", "pipe", "inherit"] });
}

// The index of the first byte where two frames differ, with the pixel it is in; null when equal.
export function firstDifference(a, b) {
  const n = Math.min(a.length, b.length);
  for (let i = 0; i < n; i++) {
    if (a[i] !== b[i]) {
      const px = Math.floor(i / 3);
      return { byte: i, x: px % WIDTH, y: Math.floor(px / WIDTH), got: a[i], expected: b[i] };
    }
  }
  return a.length === b.length ? null : { lengths: [a.length, b.length] };
}

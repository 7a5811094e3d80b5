// The report's browser test (issue 22, item 3): headless Chromium (Debian's, driven by
// playwright-core) opens report/index.html, and the test checks that every image loaded
// (naturalWidth > 0), that there is at least one, and that no console error, page error or
// failed request occurred.
// usage: node .ci/browser-test.mjs OUT_DIR/report/index.html
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { chromium } from "playwright-core";

const page_path = path.resolve(process.argv[2] ?? "out/report/index.html");
if (!fs.existsSync(page_path)) {
  console.error(`browser-test: ${page_path} does not exist`);
  process.exit(1);
}
const profile = fs.mkdtempSync(path.join(os.tmpdir(), "report-chromium-"));
const ctx = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
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
const problems = [];
try {
  const page = await ctx.newPage();
  page.on("console", (m) => {
    if (m.type() === "error") problems.push(`console error: ${m.text()}`);
  });
  page.on("pageerror", (e) => problems.push(`page error: ${e.message}`));
  page.on("requestfailed", (r) => problems.push(`request failed: ${r.url()} (${r.failure()?.errorText})`));
  await page.goto(pathToFileURL(page_path).href, { waitUntil: "load", timeout: 120000 });
  // Every image decoded: complete, with a natural width.
  await page.waitForFunction(() => Array.from(document.images).every((i) => i.complete), null, { timeout: 120000 });
  const imgs = await page.evaluate(() =>
    Array.from(document.images).map((i) => ({ src: i.getAttribute("src"), w: i.naturalWidth, h: i.naturalHeight })),
  );
  const broken = imgs.filter((i) => !(i.w > 0 && i.h > 0));
  for (const b of broken) problems.push(`image not loaded: ${b.src}`);
  if (imgs.length === 0) problems.push("the report shows no image");
  const anims = imgs.filter((i) => /\.apng$/.test(i.src)).length;
  if (process.env.SCREENSHOT) await page.screenshot({ path: process.env.SCREENSHOT, fullPage: false });
  console.log(`browser: ${imgs.length} images (${anims} animated) loaded of ${imgs.length}, ${problems.length} problems`);
} finally {
  await ctx.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
for (const p of problems) console.log(`  ${p}`);
process.exit(problems.length ? 1 : 0);

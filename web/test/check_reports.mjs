// Opens report.html files in headless Chromium (Debian's /usr/bin/chromium,
// driven by playwright-core) and checks what a reader would see: no console
// errors or page errors, no request leaving the file (the page is
// self-contained), every <img> decoded, the 3D canvas drawn (pixels other
// than the background in a screenshot of it), the file at most 10 MB and
// ready within 3 s (--max-ready-ms). Screenshots (page and canvas) go to --shots.
//
//   node web/test/check_reports.mjs [--max-ready-ms MS] [--shots DIR] [--json FILE] REPORT.html...
//
// Exit 0 when every report passes, 1 otherwise (each failure one line).
import { chromium } from 'playwright-core';
import { PNG } from 'pngjs';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const MAX_BYTES = 10 * 1024 * 1024;
let maxReadyMs = 3000;
const BACKGROUND = [0xee, 0xf0, 0xf4];

const args = process.argv.slice(2);
let shots = null, jsonOut = null;
const reports = [];
for (let i = 0; i < args.length; ++i) {
  if (args[i] === '--shots') shots = args[++i];
  else if (args[i] === '--json') jsonOut = args[++i];
  else if (args[i] === '--max-ready-ms') maxReadyMs = Number(args[++i]);
  else reports.push(args[i]);
}
if (!reports.length) {
  console.error('usage: check_reports.mjs [--max-ready-ms MS] [--shots DIR] [--json FILE] REPORT.html...');
  process.exit(2);
}
if (shots) fs.mkdirSync(shots, { recursive: true });

function drawnPixels(buffer) {
  const png = PNG.sync.read(buffer);
  let drawn = 0;
  for (let i = 0; i < png.data.length; i += 4) {
    const d = Math.abs(png.data[i] - BACKGROUND[0]) + Math.abs(png.data[i + 1] - BACKGROUND[1]) + Math.abs(png.data[i + 2] - BACKGROUND[2]);
    if (d > 24) ++drawn;
  }
  return { drawn, total: png.width * png.height };
}

const executablePath = process.env.CHROMIUM || '/usr/bin/chromium';
const browser = await chromium.launch({
  executablePath,
  // No GPU here: WebGL on SwiftShader, Chromium's software renderer.
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-sandbox'],
});
const results = [];
let failed = 0;
for (const report of reports) {
  const file = path.resolve(report);
  const name = path.basename(path.dirname(file));
  const problems = [];
  const bytes = fs.statSync(file).size;
  if (bytes > MAX_BYTES) problems.push(`${(bytes / 1048576).toFixed(1)} MB, over 10 MB`);
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console error: ${m.text()}`); });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  const url = pathToFileURL(file).href;
  await page.route('**/*', (route) => {
    const u = route.request().url();
    if (u === url || u.startsWith('data:') || u.startsWith('blob:')) return route.continue();
    problems.push(`requested ${u}`);
    return route.abort();
  });
  const started = Date.now();
  await page.goto(url, { waitUntil: 'load', timeout: 30000 });
  await page.waitForSelector('body[data-ready="true"]', { timeout: 30000 }).catch(() => problems.push('never ready'));
  // Textures decode asynchronously: wait for the images the page holds.
  await page.evaluate(() => Promise.all([...document.images].map((img) => (img.complete ? null : new Promise((r) => { img.onload = r; img.onerror = r; })))));
  const readyMs = Date.now() - started;
  if (readyMs > maxReadyMs) problems.push(`ready after ${readyMs} ms, over ${maxReadyMs} ms`);
  const images = await page.evaluate(() => [...document.images].map((img) => ({ src: img.alt, ok: img.complete && img.naturalWidth > 0 })));
  for (const img of images) if (!img.ok) problems.push(`image did not load: ${img.src}`);
  const kind = await page.evaluate(() => JSON.parse(document.getElementById('spec2fab-data').textContent).kind);
  let canvas = null;
  const viewer = await page.$('.viewer canvas');
  if (viewer) {
    await viewer.scrollIntoViewIfNeeded();
    await page.waitForTimeout(300);
    const shot = await viewer.screenshot();
    canvas = drawnPixels(shot);
    if (canvas.drawn < 0.01 * canvas.total) problems.push(`3D canvas blank: ${canvas.drawn} of ${canvas.total} pixels drawn`);
    if (shots) fs.writeFileSync(path.join(shots, `${name}_3d.png`), shot);
  } else if (kind === 'run') {
    problems.push('no 3D view');
  }
  const charts = await page.$$eval('.chart canvas', (list) => list.length);
  // The charts the data calls for: a bench's two per problem that ran, a run's convergence when it kept traces.
  const expectedCharts = await page.evaluate(() => {
    const d = JSON.parse(document.getElementById('spec2fab-data').textContent);
    if (d.kind === 'bench') return 2 * d.report.problems.filter((p) => p.charts).length;
    return d.convergence?.traces?.length ? 1 : 0;
  });
  if (charts !== expectedCharts) problems.push(`${charts} charts drawn, ${expectedCharts} expected`);
  if (shots) {
    await page.evaluate(() => window.scrollTo(0, 0));
    await page.screenshot({ path: path.join(shots, `${name}_page.png`), fullPage: false });
  }
  await page.close();
  results.push({ report: file, kind, bytes, ready_ms: readyMs, images: images.length, charts, canvas, problems });
  const status = problems.length ? 'FAIL' : 'ok';
  console.log(`${status} ${report}: ${(bytes / 1048576).toFixed(2)} MB, ready in ${readyMs} ms, ${images.length} images, ${charts} charts` +
    (canvas ? `, 3D ${(100 * canvas.drawn / canvas.total).toFixed(0)} % drawn` : ''));
  for (const p of problems) console.log(`  ${p}`);
  if (problems.length) ++failed;
}
await browser.close();
if (jsonOut) fs.writeFileSync(jsonOut, JSON.stringify(results, null, 1) + '\n');
process.exit(failed ? 1 : 0);

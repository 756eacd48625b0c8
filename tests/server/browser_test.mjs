#!/usr/bin/env node
// The page of `unique3d serve` in a real browser: Debian's chromium, headless, driven by puppeteer-core
// (tools/node_modules, installed by scripts/install_deps.sh). It starts the server, opens the page,
// uploads the bundled example's eight views through the page's file input, submits, waits for the job
// to end, checks that the viewer shows the mesh (the viewer's area of a screenshot differs from its
// empty background), downloads the GLB through the page's button and validates it with the Khronos
// validator. The screenshot is kept as an artefact. Exits 0 on success, 1 on a failure, 77 (ctest's
// skip) only when chromium cannot start, saying why.
// Usage: node tests/server/browser_test.mjs --cli build/unique3d --out DIR
import { spawn, spawnSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const args = Object.fromEntries(process.argv.slice(2).reduce((acc, a, i, all) => (a.startsWith('--') ? [...acc, [a.slice(2), all[i + 1]]] : acc), []));
const cli = path.resolve(args.cli || path.join(root, 'build/unique3d'));
const out = path.resolve(args.out || path.join(root, 'build/test-artifacts'));
fs.mkdirSync(out, { recursive: true });

function fail(message) {
  console.error(`browser test: FAILED: ${message}`);
  process.exitCode = 1;
  throw new Error(message);
}

const require = createRequire(path.join(root, 'tools/package.json'));
let puppeteer;
try {
  puppeteer = require('puppeteer-core');
} catch (e) {
  fail('puppeteer-core is not installed in tools/node_modules (run scripts/install_deps.sh)');
}
const chromium = ['/usr/bin/chromium', '/usr/bin/chromium-browser'].find((p) => fs.existsSync(p));
if (!chromium) fail('chromium is not installed (run scripts/install_deps.sh)');

// The server on a free port, with its own jobs folder; its URL from its first line.
const jobs = fs.mkdtempSync(path.join(os.tmpdir(), 'u3d-browser-'));
const server = spawn(cli, ['serve', '--port', '0', '--jobs-dir', jobs], { stdio: ['ignore', 'ignore', 'pipe'] });
let serverLog = '';
const url = await new Promise((resolve, reject) => {
  const timer = setTimeout(() => reject(new Error('the server printed no URL within 30 s:\n' + serverLog)), 30000);
  server.stderr.on('data', (d) => {
    serverLog += d;
    const m = /serving on (http:\/\/\S+)/.exec(serverLog);
    if (m) { clearTimeout(timer); resolve(m[1]); }
  });
  server.on('exit', (code) => reject(new Error(`the server exited (${code}):\n${serverLog}`)));
}).catch((e) => fail(e.message));

let browser;
const cleanup = async () => {
  if (browser) await browser.close().catch(() => {});
  server.kill('SIGTERM');
  fs.rmSync(jobs, { recursive: true, force: true });
};

try {
  try {
    browser = await puppeteer.launch({
      executablePath: chromium,
      headless: true,
      args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--window-size=1280,900'],
      defaultViewport: { width: 1280, height: 900 },
      timeout: 60000,
    });
  } catch (e) {
    // As GoogleTest words a skip, so that scripts/skipped_tests.sh finds the reason in ctest's JUnit file.
    console.log(`browser_test.mjs: Skipped\nchromium cannot start here: ${e.message.split('\n')[0]}\n`);
    process.exitCode = 77;
    throw e;
  }
  const page = await browser.newPage();
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(m.text()); });
  await page.goto(url, { waitUntil: 'networkidle0', timeout: 60000 });
  const downloads = fs.mkdtempSync(path.join(os.tmpdir(), 'u3d-downloads-'));
  const cdp = await page.createCDPSession();
  await cdp.send('Browser.setDownloadBehavior', { behavior: 'allow', downloadPath: downloads });

  // Upload the bundled example's views through the file input, as a person choosing the files would.
  const views = path.join(root, 'examples/spot/views');
  const files = ['front', 'right', 'back', 'left'].flatMap((v) => [`${v}_rgb.png`, `${v}_normal.png`]).map((f) => path.join(views, f));
  const input = await page.$('#file-views');
  await input.uploadFile(...files);
  await page.waitForFunction(() => !document.querySelector('#submit-views').disabled, { timeout: 10000 });
  await page.click('#submit-views');

  await page.waitForFunction(() => /^(done|failed|cancelled)/.test(document.querySelector('#job-state').textContent), { timeout: 300000 });
  const jobState = await page.$eval('#job-state', (e) => e.textContent);
  if (!jobState.startsWith('done')) fail(`the job ended ${jobState}: ${await page.$eval('#job-error', (e) => e.textContent)}`);
  const stages = await page.$$eval('#stages tr', (rows) => rows.map((r) => r.cells[0].textContent));
  for (const s of ['initial mesh', 'coarse', 'refine']) if (!stages.includes(s)) fail(`the stage list lacks '${s}' (has ${stages.join(', ')})`);
  const images = await page.$$eval('#gallery img', (imgs) => imgs.map((i) => i.alt));
  if (!images.some((a) => a.includes('mesh views'))) fail(`the gallery lacks the preview of the views (has ${images.join(', ')})`);

  // The viewer has loaded the mesh and drawn it: let it turn a moment, then look at its area.
  await page.waitForFunction(() => document.querySelector('#viewer') && document.querySelector('#viewer').loaded, { timeout: 60000 });
  await new Promise((r) => setTimeout(r, 2500));
  const shot = path.join(out, 'server_page.png');
  await page.screenshot({ path: shot });
  const box = await (await page.$('#viewer')).boundingBox();
  const changed = await page.evaluate(async (png, box) => {
    const img = new Image();
    img.src = 'data:image/png;base64,' + png;
    await img.decode();
    const canvas = document.createElement('canvas');
    canvas.width = img.width;
    canvas.height = img.height;
    const ctx = canvas.getContext('2d');
    ctx.drawImage(img, 0, 0);
    const x0 = Math.ceil(box.x) + 2, y0 = Math.ceil(box.y) + 2, w = Math.floor(box.width) - 4, h = Math.floor(box.height) - 4;
    const d = ctx.getImageData(x0, y0, w, h).data;
    // The empty viewer is a vertical gradient: each row's background is its first pixel's colour.
    let differing = 0;
    for (let y = 0; y < h; ++y) {
      const r0 = d[4 * y * w], g0 = d[4 * y * w + 1], b0 = d[4 * y * w + 2];
      for (let x = 0; x < w; ++x) {
        const i = 4 * (y * w + x);
        if (Math.max(Math.abs(d[i] - r0), Math.abs(d[i + 1] - g0), Math.abs(d[i + 2] - b0)) > 24) ++differing;
      }
    }
    return differing / (w * h);
  }, fs.readFileSync(shot).toString('base64'), box);
  console.log(`browser test: ${(100 * changed).toFixed(1)} % of the viewer's pixels show the mesh (screenshot ${shot})`);
  if (!(changed > 0.02)) fail(`the viewer looks empty: ${(100 * changed).toFixed(2)} % of its pixels differ from its background`);

  // Download the GLB through the page's button and validate it.
  await page.click('#download-glb');
  const glb = path.join(downloads, 'unique3d.glb');
  const deadline = Date.now() + 30000;
  while (!fs.existsSync(glb) && Date.now() < deadline) await new Promise((r) => setTimeout(r, 200));
  if (!fs.existsSync(glb)) fail(`no GLB was downloaded into ${downloads} (has ${fs.readdirSync(downloads).join(', ')})`);
  await new Promise((r) => setTimeout(r, 500));
  const validation = spawnSync('node', [path.join(root, 'tools/validate_gltf.mjs'), glb], { encoding: 'utf8' });
  if (validation.status !== 0) fail(`the downloaded GLB does not validate:\n${validation.stdout}${validation.stderr}`);
  console.log(`browser test: downloaded ${fs.statSync(glb).size} bytes of GLB; ${validation.stdout.trim().split('\n')[0]}`);
  fs.rmSync(downloads, { recursive: true, force: true });
  if (pageErrors.length) fail(`the page reported errors: ${pageErrors.join('; ')}`);
  console.log('browser test: passed');
} catch (e) {
  if (process.exitCode === undefined) {
    console.error(`browser test: FAILED: ${e.message}`);
    process.exitCode = 1;
  }
} finally {
  await cleanup();
}

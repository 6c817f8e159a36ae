#!/usr/bin/env node
// check-report REPORT.html SCREENSHOT.png: opens the report in Debian's
// headless chromium (driven by playwright-core), records console errors and
// every request, saves a full-page screenshot, and prints a JSON summary.
// Exits 0 when the page loaded with no console error and requested nothing
// outside the report's own folder (data: URIs are inline), 1 otherwise.
'use strict';
const path = require('path');
const { chromium } = require('playwright-core');

async function main() {
  const [report, screenshot] = process.argv.slice(2);
  if (!report || !screenshot) {
    console.error('usage: check-report REPORT.html SCREENSHOT.png');
    process.exit(2);
  }
  const dir = path.dirname(path.resolve(report));
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--no-first-run'],
  });
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  const errors = [];
  const outside = [];
  const requests = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('request', (r) => {
    const url = r.url();
    requests.push(url.startsWith('data:') ? 'data:' : url);
    if (url.startsWith('data:')) return;
    if (url.startsWith('file://') && decodeURIComponent(new URL(url).pathname).startsWith(dir)) return;
    outside.push(url);
  });
  page.on('requestfailed', (r) => {
    if (!r.url().startsWith('data:')) errors.push('request failed: ' + r.url());
  });
  await page.goto('file://' + path.resolve(report), { waitUntil: 'load' });
  const sections = await page.$$eval('section h2', (hs) => hs.map((h) => h.textContent));
  const images = await page.$$eval('img', (is) => is.map((i) => i.complete && i.naturalWidth > 0));
  const svgs = await page.$$eval('svg circle', (cs) => cs.length);
  await page.screenshot({ path: screenshot, fullPage: true });
  await browser.close();
  const summary = {
    report, sections, images: images.length, broken_images: images.filter((ok) => !ok).length,
    plot_points: svgs, console_errors: errors, outside_requests: outside,
    requests: requests.length,
  };
  console.log(JSON.stringify(summary, null, 1));
  process.exit(errors.length === 0 && outside.length === 0 && summary.broken_images === 0 ? 0 : 1);
}

main().catch((e) => { console.error('check-report: ' + e); process.exit(1); });

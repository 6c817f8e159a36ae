#!/usr/bin/env node
// check-report SCREENSHOT.png REPORT.html [REPORT.html ...]: opens each report
// in Debian's headless chromium (driven by playwright-core), one browser for
// all of them (its start costs as much as a page), records console errors and
// every request, saves a full-page screenshot of the first report, and prints
// a JSON array with one summary per report. Exits 0 when every page loaded
// with no console error, no broken image and nothing requested outside its
// report's folder (data: URIs are inline), 1 otherwise.
'use strict';
const path = require('path');
const { chromium } = require('playwright-core');

async function check(browser, report, screenshot) {
  const dir = path.dirname(path.resolve(report));
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
  // A full-page screenshot costs more than loading the page: one is enough to look at.
  if (screenshot) await page.screenshot({ path: screenshot, fullPage: true });
  await page.close();
  const summary = {
    report, sections, images: images.length, broken_images: images.filter((ok) => !ok).length,
    plot_points: svgs, console_errors: errors, outside_requests: outside,
    requests: requests.length,
  };
  summary.ok = errors.length === 0 && outside.length === 0 && summary.broken_images === 0;
  return summary;
}

async function main() {
  const [screenshot, ...reports] = process.argv.slice(2);
  if (!screenshot || reports.length === 0) {
    console.error('usage: check-report SCREENSHOT.png REPORT.html [REPORT.html ...]');
    process.exit(2);
  }
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--no-first-run'],
  });
  const summaries = [];
  for (const [i, report] of reports.entries())
    summaries.push(await check(browser, report, i === 0 ? screenshot : null));
  await browser.close();
  console.log(JSON.stringify(summaries, null, 1));
  process.exit(summaries.every((s) => s.ok) ? 0 : 1);
}

main().catch((e) => { console.error('check-report: ' + e); process.exit(1); });

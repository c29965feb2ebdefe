// Shared by the browser tests: pass/fail counting, Debian's headless chromium, and the live view
// opened on a page and waited for.
import { chromium } from "playwright-core";

/** A test's checks: `check(name, ok, detail)` prints an ok/FAIL line and counts it; `finish(label)`
 *  prints the totals and exits, with 1 if any check failed. */
export function checker() {
  let passed = 0, failed = 0;
  return {
    check(name, ok, detail = "") {
      if (ok) { passed++; console.log(`ok   ${name}`); }
      else { failed++; console.log(`FAIL ${name} ${detail}`); }
    },
    finish(label) {
      console.log(`${label}: ${passed} passed, ${failed} failed`);
      process.exit(failed ? 1 : 0);
    },
  };
}

/** Headless chromium: $CHROMIUM, else Debian's /usr/bin/chromium. */
export function launchBrowser() {
  return chromium.launch({ executablePath: process.env.CHROMIUM || "/usr/bin/chromium", args: ["--no-sandbox"] });
}

/** A 1280 × 1000 page (one device pixel per CSS pixel, so screenshots compare). */
export function newPage(browser) {
  return browser.newPage({ viewport: { width: 1280, height: 1000 }, deviceScaleFactor: 1 });
}

/** Opens the view at `url` and waits (20 s at most) until it has drawn its map. */
export async function openView(page, url) {
  await page.goto(url);
  await page.waitForFunction(() => window.skyplanView && window.skyplanView.state.ready, null, { timeout: 20000 });
}

/** Waits (20 s at most) until the view's vehicle state starts with `prefix`. */
export function waitForVehicleState(page, prefix) {
  return page.waitForFunction((p) => document.getElementById("v-state").textContent.startsWith(p), prefix, { timeout: 20000 });
}

/** The canvas's colour `[r, g, b, a]` at a local point `[north_m, east_m]`. */
export function pixelAt(page, ne) {
  return page.evaluate(([n, e]) => {
    const c = document.getElementById("map");
    const r = c.getBoundingClientRect();
    const p = window.skyplanView.toClient(n, e);
    return Array.from(c.getContext("2d").getImageData(Math.round(p.x - r.left), Math.round(p.y - r.top), 1, 1).data);
  }, ne);
}

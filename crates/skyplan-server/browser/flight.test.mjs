// A flight on the page: the view_flight example, or `skyplan fly --sim --view` (browser/fly_sim.sh), serves the page
// and publishes a route and the vehicle's state at 10 Hz; the page shows the route, moves the
// marker, draws the trail and shows the state until MANUAL after landing.
// Usage: node flight.test.mjs VIEW_FLIGHT_BIN|fly_sim.sh SCREENSHOT.png
import fs from "node:fs";
import { freePort, startProcess } from "./common.mjs";
import { checker, launchBrowser, newPage, openView, waitForVehicleState } from "./view.mjs";

const [bin, screenshot] = process.argv.slice(2);
if (!bin || !screenshot) throw new Error("usage: node flight.test.mjs VIEW_FLIGHT_BIN SCREENSHOT.png");
const { check, finish } = checker();

const port = await freePort();
const flight = await startProcess(bin, [`127.0.0.1:${port}`, "10"]);
const browser = await launchBrowser();
try {
  const page = await newPage(browser);
  await openView(page, flight.url);
  await waitForVehicleState(page, "WAYPOINT");
  const route = await page.evaluate(() => window.skyplanView.state.route);
  check("the route being flown is shown", Array.isArray(route) && route.length >= 2, JSON.stringify(route));
  const states = [];
  const seen = await page.evaluate(() => new Promise((resolve) => {
    const seen = [];
    const es = new EventSource("/api/events");
    es.addEventListener("flight", (m) => {
      const s = JSON.parse(m.data).state;
      if (seen[seen.length - 1] !== s) seen.push(s);
      if (s === "MANUAL") { es.close(); resolve(seen); }
    });
    setTimeout(() => resolve(seen), 60000);
  }));
  states.push(...seen);
  check("the states run on to MANUAL after landing", /LANDING( DISARMING)? MANUAL$/.test(states.join(" ")), states.join(" "));
  await page.waitForFunction(() => document.getElementById("v-state").textContent === "MANUAL", null, { timeout: 5000 });
  check("the page shows MANUAL", true);
  const trail = await page.evaluate(() => window.skyplanView.state.trail.length);
  check("the trail was drawn from the updates", trail > 50, String(trail));
  const log = await page.textContent("#log");
  check("the state changes are logged", /vehicle LANDING/.test(log) && /vehicle MANUAL/.test(log), log.slice(0, 300));
  await page.screenshot({ path: screenshot, fullPage: true });
  check("a screenshot was saved", fs.statSync(screenshot).size > 20000, screenshot);
} finally {
  await browser.close();
  flight.stop();
}
finish("flight");

// `skyplan sim --view`: the simulator alone serves the page and publishes its state (pose,
// heading, mode, armed) and what its obstacle sensor sees at 10 Hz; the page shows the vehicle in
// its mode and draws the sensed points, which lie on the hidden box's face 25 m east of home.
// Usage: node sim_view.test.mjs SKYPLAN_BIN
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { freePort, startProcess } from "./common.mjs";
import { checker, launchBrowser, newPage, openView, waitForVehicleState } from "./view.mjs";

const [bin] = process.argv.slice(2);
if (!bin) throw new Error("usage: node sim_view.test.mjs SKYPLAN_BIN");
const { check, finish } = checker();

const dir = fs.mkdtempSync(path.join(os.tmpdir(), "skyplan-sim-view-"));
const hidden = path.join(dir, "hidden.csv");
fs.writeFileSync(hidden, "lat0 37.792480, lon0 -122.397450\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n0,27,10,10,2,10\n");
const port = await freePort();
const sim = await startProcess(bin, ["sim", "--listen", "tcp:127.0.0.1:0", "--view", `127.0.0.1:${port}`,
  "--hidden", hidden, "--ekf-delay-s", "0", "--duration-s", "60"]);
const browser = await launchBrowser();
try {
  const page = await newPage(browser);
  await openView(page, sim.url);
  await waitForVehicleState(page, "STABILIZE");
  check("the page shows the simulator's mode", true);
  const v = await page.evaluate(() => window.skyplanView.state.vehicle);
  check("the vehicle is at home", v && Math.abs(v.north_m) < 0.01 && Math.abs(v.east_m) < 0.01 && v.armed === false, JSON.stringify(v));
  await page.waitForFunction(() => window.skyplanView.state.lastHits.length > 0, null, { timeout: 20000 });
  const hits = await page.evaluate(() => window.skyplanView.state.lastHits);
  check("the sensed points lie on the hidden box's west face", hits.length >= 5 && hits.every(([n, e]) => Math.abs(e - 25) < 0.01 && Math.abs(n) <= 10.01), JSON.stringify(hits));
  const sensed = await page.textContent("#v-sensed");
  check("the sensed count is shown", /points now/.test(sensed), sensed);
} finally {
  await browser.close();
  sim.stop();
  fs.rmSync(dir, { recursive: true, force: true });
}
finish("sim view");

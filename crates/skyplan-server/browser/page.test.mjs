// The page in a real browser (Debian's chromium through playwright-core): the map is drawn, a
// click sets the start, another the goal, the route comes back and its shown length is
// `skyplan plan --json`'s cost_m for the same request; the roadmap toggle draws the roadmap.
// Usage: node page.test.mjs SKYPLAN_BIN SCREENSHOT.png
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { startServer, loadGrid, connectedClearCells, nearest } from "./common.mjs";
import { checker, launchBrowser, newPage, openView } from "./view.mjs";

const [bin, screenshot] = process.argv.slice(2);
if (!bin || !screenshot) throw new Error("usage: node page.test.mjs SKYPLAN_BIN SCREENSHOT.png");
const { check, finish } = checker();

const server = await startServer(bin);
const browser = await launchBrowser();
try {
  const page = await newPage(browser);
  const consoleErrors = [];
  // The browser logs the 422s the invalid start below asks for, and the 503s the page retries.
  page.on("console", (m) => { if (m.type() === "error" && !/status of (422|503)/.test(m.text())) consoleErrors.push(m.text()); });
  page.on("pageerror", (e) => consoleErrors.push(String(e)));
  await openView(page, server.url);

  // The map canvas is drawn: many non-background pixels, several colours.
  const pixels = await page.evaluate(() => {
    const c = document.getElementById("map");
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let drawn = 0;
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) {
      if (d[i + 3] > 0) drawn++;
      if (i % 64 === 0) colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
    }
    return { drawn, total: d.length / 4, colours: colours.size };
  });
  check("the map canvas is drawn", pixels.drawn > 0.5 * pixels.total && pixels.colours > 10, JSON.stringify(pixels));
  // At 1400 × 900 the whole map — its east axis and scale bar at the canvas's bottom — and the
  // status line fit in the window, without scrolling.
  await page.setViewportSize({ width: 1400, height: 900 });
  await page.waitForTimeout(300);
  const fold = await page.evaluate(() => ({
    canvas: document.getElementById("map").getBoundingClientRect().bottom,
    status: document.getElementById("status").getBoundingClientRect().bottom,
    height: window.innerHeight,
  }));
  check("at 1400 × 900 the map and the status line are above the fold", fold.canvas <= fold.height && fold.status <= fold.height, JSON.stringify(fold));
  await page.setViewportSize({ width: 1280, height: 1000 });
  await page.waitForTimeout(300);
  const name = await page.textContent("#map-name");
  check("the header names the map and its buildings", /3845 buildings/.test(name), name);

  // Far-apart free points with 4 m of clearance (a click lands within a pixel of them).
  const grid = await loadGrid(server.url, 5, 5);
  const cells = connectedClearCells(grid, [0, 0], 4);
  const start = nearest(cells, [-250, -300]);
  const goal = nearest(cells, [400, 380]);
  for (const p of [start, goal]) {
    const { x, y } = await page.evaluate(([n, e]) => window.skyplanView.toClient(n, e), p);
    await page.mouse.click(x, y);
  }
  await page.waitForFunction(() => window.skyplanView.state.planned >= 1, null, { timeout: 20000 });
  const shown = (await page.textContent("#length")).trim();
  const request = await page.evaluate(() => window.skyplanView.state.lastRequest);
  check("the page asked for the clicked points", request && Math.hypot(request.start_ne[0] - start[0], request.start_ne[1] - start[1]) < 3,
    JSON.stringify({ request, start }));

  // The same request through the CLI.
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "skyplan-page-"));
  const cli = JSON.parse(execFileSync(bin, [
    "plan", "--json", "--out", path.join(tmp, "waypoints.json"),
    "--planner", request.planner, "--alt-m", String(request.alt_m), "--safety-m", String(request.safety_m),
    "--start-ne", request.start_ne.join(","), "--goal-ne", request.goal_ne.join(","),
  ], { encoding: "utf8" }));
  fs.rmSync(tmp, { recursive: true, force: true });
  const want = `${cli.cost_m.toFixed(1)} m`;
  check("the shown length is skyplan plan --json's cost_m", shown === want, `shown ${shown}, CLI ${want}`);
  const plan = await page.evaluate(() => window.skyplanView.state.plan);
  check("the page's plan has the CLI's waypoints", plan && JSON.stringify(plan.waypoints) === JSON.stringify(cli.waypoints));
  const wps = (await page.textContent("#waypoints")).trim();
  check("the waypoint count is shown", wps === String(cli.waypoints.length), wps);
  const time = (await page.textContent("#time")).trim();
  check("the planning time is shown", /ms planning/.test(time), time);

  // The event stream brought this plan back to the page.
  await page.waitForFunction(() => /plan #\d+ jps: /.test(document.getElementById("log").textContent), null, { timeout: 10000 });
  check("the plan event arrived over /api/events", true);

  // Toggle the roadmap: PRM with geometry draws its roadmap.
  await page.selectOption("#planner", "prm");
  await page.check("#geometry");
  await page.waitForFunction(() => {
    const p = window.skyplanView.state.plan;
    return p && p.planner === "prm" && p.geometry && p.geometry.edges.length > 0;
  }, null, { timeout: 30000 });
  check("the roadmap toggle returns and draws the roadmap", true);

  // The trajectory toggle: the plan comes back with its trajectory (the CLI's duration for the
  // same request), drawn by speed; pointing at a sample shows its time and speed.
  await page.uncheck("#geometry");
  await page.selectOption("#planner", "jps");
  await page.check("#trajectory");
  await page.waitForFunction(() => {
    const p = window.skyplanView.state.plan;
    return p && p.planner === "jps" && p.trajectory && p.trajectory.samples.length > 10;
  }, null, { timeout: 30000 });
  const traj = await page.evaluate(() => window.skyplanView.state.plan.trajectory);
  const cliTraj = JSON.parse(execFileSync(bin, [
    "plan", "--json", "--trajectory", "--planner", "jps", "--alt-m", String(request.alt_m), "--safety-m", String(request.safety_m),
    "--start-ne", request.start_ne.join(","), "--goal-ne", request.goal_ne.join(","),
  ], { encoding: "utf8", cwd: os.tmpdir() })).trajectory;
  check("the page's trajectory lasts as long as skyplan plan --trajectory's",
    Math.abs(traj.duration_s - cliTraj.duration_s) < 1e-6, `${traj.duration_s} vs ${cliTraj.duration_s}`);
  const summary = (await page.textContent("#traj")).trim();
  check("the trajectory's duration is shown", summary.startsWith(`${traj.duration_s.toFixed(1)} s, top `), summary);
  const row = traj.samples[Math.floor(traj.samples.length / 2)];
  const at = await page.evaluate(([n, e]) => window.skyplanView.toClient(n, e), [row[1], row[2]]);
  await page.mouse.move(at.x, at.y);
  await page.waitForFunction(() => /^t /.test(document.getElementById("traj-at").textContent), null, { timeout: 5000 });
  const pointed = (await page.textContent("#traj-at")).trim();
  const speed = Math.hypot(row[4], row[5], row[6]);
  // Samples are 0.1 s apart and the nearest one to the pointer is shown: within a sample or two.
  const shownT = Number(/^t ([0-9.]+) s, ([0-9.]+) m\/s/.exec(pointed)?.[1]);
  const shownV = Number(/^t ([0-9.]+) s, ([0-9.]+) m\/s/.exec(pointed)?.[2]);
  check("pointing at the trajectory shows the time and speed there",
    Math.abs(shownT - row[0]) <= 0.25 && Math.abs(shownV - speed) <= 0.5, `${pointed} vs t ${row[0]}, ${speed} m/s`);
  await page.uncheck("#trajectory");

  // A start inside a building: the status line says so.
  const b = grid.map.obstacles.filter((o) => o[5] > 10).sort((x, y) => y[2] * y[3] - x[2] * x[3])[0];
  await page.selectOption("#planner", "jps");
  await page.uncheck("#geometry");
  for (const p of [[b[0], b[1]], goal]) {
    const { x, y } = await page.evaluate(([n, e]) => window.skyplanView.toClient(n, e), p);
    await page.mouse.click(x, y);
  }
  await page.waitForFunction(() => document.getElementById("status").className === "error", null, { timeout: 10000 });
  const status = await page.textContent("#status");
  check("a start in a building is reported on the status line", /invalid_start/.test(status), status);

  // Back to a good route with the Voronoi roadmap for the picture.
  await page.selectOption("#planner", "voronoi");
  await page.check("#geometry");
  for (const p of [start, goal]) {
    const { x, y } = await page.evaluate(([n, e]) => window.skyplanView.toClient(n, e), p);
    await page.mouse.click(x, y);
  }
  try {
    await page.waitForFunction(() => { const p = window.skyplanView.state.plan; return p && p.planner === "voronoi"; }, null, { timeout: 30000 });
  } catch (e) {
    console.log("STATUS", await page.textContent("#status"), JSON.stringify(await page.evaluate(() => window.skyplanView.state.lastRequest)));
    throw e;
  }
  await page.screenshot({ path: screenshot, fullPage: true });
  check("a screenshot was saved", fs.statSync(screenshot).size > 20000, screenshot);
  check("no errors in the page's console", consoleErrors.length === 0, consoleErrors.join("; "));
} finally {
  await browser.close();
  server.stop();
}
finish("page");

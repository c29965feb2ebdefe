// `skyplan serve` on real-world maps: over a DEM (`--terrain`) the page draws the ground's
// contours from /api/map's `terrain`; on a GeoJSON footprint map it draws the footprints as
// polygons shaded by height. Checked on the canvas's own pixels, with the other map as control.
// Usage: node real_map.test.mjs SKYPLAN_BIN (run from anywhere; data/ is found from here)
import path from "node:path";
import { fileURLToPath } from "node:url";
import { connectedClearCells, loadGrid, startServer } from "./common.mjs";
import { checker, launchBrowser, newPage, openView, pixelAt } from "./view.mjs";

const [bin] = process.argv.slice(2);
if (!bin) throw new Error("usage: node real_map.test.mjs SKYPLAN_BIN");
const data = path.resolve(path.dirname(fileURLToPath(import.meta.url)), "../../../data");
const { check, finish } = checker();

/** Pixels of the canvas coloured like the contours (a brown no other layer uses). */
function countContourPixels(page) {
  return page.evaluate(() => {
    const c = document.getElementById("map");
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const [r, g, b] = [d[i], d[i + 1], d[i + 2]];
      if (r > 130 && r < 205 && g > 90 && g < 160 && b > 40 && b < 125 && r - b > 40) n++;
    }
    return n;
  });
}

const browser = await launchBrowser();
const servers = [];
try {
  // Over the Jacksboro hills: contours.
  const hills = await startServer(bin, ["--map", path.join(data, "terrain/blocks.csv"), "--terrain", path.join(data, "terrain/jacksboro.tif")]);
  servers.push(hills);
  const map = await (await fetch(`${hills.url}api/map`)).json();
  const t = map.terrain;
  check("/api/map carries the ground's contours", t && t.contours.length >= 5 && t.contours.every((c) => c.segments.length > 0), JSON.stringify(t && { n: t.contours.length, interval: t.interval_m }));
  check("the contours span the ground's heights", t && t.contours[0].level_m >= t.lowest_m && t.contours[t.contours.length - 1].level_m <= t.highest_m);
  let page = await newPage(browser);
  await openView(page, hills.url);
  const name = await page.textContent("#map-name");
  check("the header says the contour interval", new RegExp("ground contours every " + t.interval_m + " m").test(name), name);
  const brown = await countContourPixels(page);
  check("the page draws the contours", brown > 500, `${brown} contour pixels`);
  await page.close();

  // GeoJSON footprints (no terrain): polygons, no contours.
  const geo = await startServer(bin, ["--map", path.join(data, "footprints-sample.geojson")]);
  servers.push(geo);
  const fmap = await (await fetch(`${geo.url}api/map`)).json();
  check("/api/map carries the footprints", fmap.kind === "footprints" && fmap.footprints.length > 10 && fmap.terrain === null, `${fmap.kind}, ${fmap.footprints.length}`);
  page = await newPage(browser);
  await openView(page, geo.url);
  const fname = await page.textContent("#map-name");
  check("the header counts the footprints", new RegExp(fmap.footprints.length + " buildings").test(fname), fname);
  // Inside each of the first footprints (the mean of a convex outer ring), the building's
  // shade: bluish grey, where the background and the margin are not.
  // Even-odd over all rings (holes are out), and 2 m clear of every edge.
  const inRings = (p, rings) => {
    let odd = false;
    for (const ring of rings)
      for (let i = 0, j = ring.length - 1; i < ring.length; j = i++) {
        const [a, b] = [ring[i], ring[j]];
        if ((a[0] > p[0]) !== (b[0] > p[0]) && p[1] < ((b[1] - a[1]) * (p[0] - a[0])) / (b[0] - a[0]) + a[1]) odd = !odd;
      }
    return odd;
  };
  const clear = (p, rings) => [[2, 0], [-2, 0], [0, 2], [0, -2], [0, 0]].every(([dn, de]) => inRings([p[0] + dn, p[1] + de], rings));
  let inside = 0, tried = 0;
  for (const f of fmap.footprints) {
    const ring = f.rings[0];
    const c = [0, 1].map((k) => ring.reduce((s, p) => s + p[k], 0) / ring.length);
    if (!clear(c, f.rings)) continue;
    const [r, , b] = await pixelAt(page, c);
    tried++;
    if (b > r + 10) inside++;
    if (tried === 8) break;
  }
  check("the page fills the footprints", tried >= 4 && inside === tried, `${inside} of ${tried}`);
  const none = await countContourPixels(page);
  check("no contours without terrain", none < 20, `${none} contour-coloured pixels`);
  await page.close();

  // No-fly zones (serve --no-fly) on the bundled city: drawn, and the page's plans avoid them.
  const zoned = await startServer(bin, ["--no-fly", path.join(data, "no-fly-sample.geojson")]);
  servers.push(zoned);
  const zmap = await (await fetch(`${zoned.url}api/map`)).json();
  const stadium = zmap.zones.find((z) => z.circle);
  check("/api/map carries the zones", zmap.zones.length === 3 && stadium && stadium.circle.radius_m === 30 && typeof zmap.no_fly === "string",
    JSON.stringify(zmap.zones.map((z) => z.feature)));
  page = await newPage(browser);
  await openView(page, zoned.url);
  const zname = await page.textContent("#map-name");
  check("the header counts the zones", /3 no-fly zones/.test(zname), zname);
  // Red over whatever lies under the stadium: its hatching and tint.
  let reddish = 0;
  const c = stadium.circle.centre_ne;
  for (let k = 0; k < 16; k++) {
    const a = (k / 16) * 2 * Math.PI;
    const [r, g] = await pixelAt(page, [c[0] + 20 * Math.cos(a), c[1] + 20 * Math.sin(a)]);
    if (r > g + 25) reddish++;
  }
  check("the page draws the stadium zone", reddish >= 4, `${reddish} of 16 reddish`);
  // A plan clicked across the stadium goes around it, and carries the zones.
  const grid = await loadGrid(zoned.url, 5, 5);
  const cells = connectedClearCells(grid, [0, 0], 4);
  const nearest = (p) => cells.reduce((b, q) => (Math.hypot(q[0] - p[0], q[1] - p[1]) < Math.hypot(b[0] - p[0], b[1] - p[1]) ? q : b));
  const ends = [nearest([c[0] - 120, c[1] - 20]), nearest([c[0] + 120, c[1] + 20])];
  const straight = Math.min(...Array.from({ length: 101 }, (_, k) => k / 100).map((t) =>
    Math.hypot(ends[0][0] + (ends[1][0] - ends[0][0]) * t - c[0], ends[0][1] + (ends[1][1] - ends[0][1]) * t - c[1])));
  check("the clicked ends' straight line crosses the stadium", straight < 30, `${straight.toFixed(1)} m from its centre`);
  for (const p of ends) {
    const { x, y } = await page.evaluate(([n, e]) => window.skyplanView.toClient(n, e), p);
    await page.mouse.click(x, y);
  }
  await page.waitForFunction(() => window.skyplanView.state.planned >= 1, null, { timeout: 20000 });
  const [request, zplan] = await page.evaluate(() => [window.skyplanView.state.lastRequest, window.skyplanView.state.plan]);
  check("the page's plan request carries the zones", request && request.no_fly === zmap.no_fly);
  let closest = Infinity;
  const w = (zplan && zplan.waypoints) || [];
  for (let i = 0; i + 1 < w.length; i++) {
    const [a, b] = [[w[i][0], w[i][1]], [w[i + 1][0], w[i + 1][1]]]; // rows are [north, east, alt, heading]
    for (let t = 0; t <= 1; t += 0.01) {
      closest = Math.min(closest, Math.hypot(a[0] + (b[0] - a[0]) * t - c[0], a[1] + (b[1] - a[1]) * t - c[1]));
    }
  }
  check("the page's route keeps the margin from the stadium", w.length > 1 && closest >= 30 + request.safety_m - 0.5, `closest ${closest.toFixed(2)} m`);
  await page.close();
} finally {
  await browser.close();
  for (const s of servers) s.stop();
}
finish("real maps on the page");

// The shared airspace on the page: intents reserved through the API (`POST /api/intents`) reach
// the page by /api/events (event `intent`), and the time slider shows each flight's volumes only
// while they are active. Checked on the canvas's own pixels.
// Usage: node intents.test.mjs SKYPLAN_BIN
import { startServer } from "./common.mjs";
import { checker, launchBrowser, newPage, openView, pixelAt } from "./view.mjs";

const [bin] = process.argv.slice(2);
if (!bin) throw new Error("usage: node intents.test.mjs SKYPLAN_BIN");
const { check, finish } = checker();

/** The intents' violet over the map's pale background (blue well above green). */
const violet = ([r, g, b]) => b > g + 15 && r > g + 8;

/** An RFC 3339 instant `s` seconds after an hour from now, in whole seconds. */
function at(s) {
  const t = Math.floor(Date.now() / 1000) * 1000 + 3600e3 + s * 1000;
  return new Date(t).toISOString().replace(".000Z", "Z");
}

const browser = await launchBrowser();
const server = await startServer(bin, []);
try {
  const page = await newPage(browser);
  await openView(page, server.url);
  check("no intent stored at first", (await page.textContent("#intents")) === "none stored" || (await page.textContent("#intents")).startsWith("0 stored"));
  const reserve = async (departure, owner) => {
    const res = await fetch(`${server.url}api/intents`, {
      method: "POST",
      headers: { "content-type": "application/json" },
      body: JSON.stringify({ plan: {}, departure, priority: 0, owner }),
    });
    return [res.status, await res.json()];
  };
  // Two flights on the city's default route, 20 minutes apart.
  const [s1, a] = await reserve(at(0), "alpha");
  const [s2, b] = await reserve(at(1200), "bravo");
  check("both intents are accepted", s1 === 201 && s2 === 201, `${s1} ${s2}`);
  await page.waitForFunction(() => window.skyplanView.state.intents.length === 2, null, { timeout: 10000 });
  check("the page heard of both through /api/events", true);
  const log = await page.textContent("#log");
  check("the event log names them", /intent accepted: alpha/.test(log) && /intent accepted: bravo/.test(log), log);
  // A point of the route 10 m along its first leg: inside the first volume of each flight.
  const [w0, w1] = [a.plan.waypoints[0], a.plan.waypoints[1]];
  const len = Math.hypot(w1[0] - w0[0], w1[1] - w0[1]);
  const p = [w0[0] + (10 * (w1[0] - w0[0])) / len, w0[1] + (10 * (w1[1] - w0[1])) / len];
  const span = await page.evaluate(() => window.skyplanView.state.span);
  const slideTo = async (ms) => {
    const v = Math.round(((ms - span[0]) / (span[1] - span[0])) * 1000);
    await page.fill("#when", String(v));
    await page.waitForTimeout(100);
  };
  const startOf = (intent) => Date.parse(intent.intent.volumes[0].time_start.value);
  const endOf = (intent) => Math.max(...intent.intent.volumes.map((v) => Date.parse(v.time_end.value)));
  await slideTo(startOf(a) + 12e3);
  const during = await pixelAt(page, p);
  check("alpha's volume is drawn while it flies", violet(during), JSON.stringify(during));
  const text = await page.textContent("#intents");
  check("the panel counts one flight in the air then", text === "2 stored, 1 flying then", text);
  await slideTo((endOf(a) + startOf(b)) / 2);
  const between = await pixelAt(page, p);
  check("nothing is drawn there between the flights", !violet(between), JSON.stringify(between));
  check("and no flight is counted then", (await page.textContent("#intents")) === "2 stored, 0 flying then");
  await slideTo(startOf(b) + 12e3);
  check("bravo's volume is drawn while it flies", violet(await pixelAt(page, p)));
  // Deleting one: the page hears of it and forgets it.
  const del = await fetch(`${server.url}api/intents/${a.intent.id}`, { method: "DELETE" });
  check("alpha is deleted", del.status === 200, String(del.status));
  await page.waitForFunction(() => window.skyplanView.state.intents.length === 1, null, { timeout: 10000 });
  check("the page drops it", /intent deleted: alpha/.test(await page.textContent("#log")));
  await page.close();
} finally {
  server.stop();
  await browser.close();
}
finish("intents");

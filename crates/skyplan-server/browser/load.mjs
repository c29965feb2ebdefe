// Load test on loopback: 200 concurrent POST /api/plan between random far-apart free points of
// the city, spread over the 2D planners of the served registry (/api/planners). The server
// queues what its workers cannot start at once: each request is answered 200, or 503 `busy`
// with Retry-After (queue full, or its wait would leave no time to plan), or 504
// `queue_timeout`/`over_budget` (its budget ran out), never anything else, and /api/status
// counts them so. Then the same 200 with clients that retry on 503, all answered 200. Prints
// the answers, throughput, p50/p99 latency and the server's peak RSS (VmHWM).
// Usage: node load.mjs SKYPLAN_BIN [N [SERVE_OPTIONS...]], e.g. `--queue-depth 0` for no queue.
import fs from "node:fs";
import { startServer, loadGrid, connectedClearCells, rng } from "./common.mjs";

const [bin, nArg, ...serveArgs] = process.argv.slice(2);
if (!bin) throw new Error("usage: node load.mjs SKYPLAN_BIN [N [SERVE_OPTIONS...]]");
const N = Number(nArg || 200);
let passed = 0, failed = 0;
function check(name, ok, detail = "") {
  if (ok) { passed++; console.log(`ok   ${name}`); }
  else { failed++; console.log(`FAIL ${name} ${detail}`); }
}
const pct = (xs, p) => { const s = [...xs].sort((a, b) => a - b); return s[Math.min(s.length - 1, Math.floor(p * s.length))]; };
const vm = (pid, key) => {
  const m = fs.readFileSync(`/proc/${pid}/status`, "utf8").match(new RegExp(`${key}:\\s+(\\d+) kB`));
  return m ? Number(m[1]) / 1024 : NaN;
};

const server = await startServer(bin, serveArgs);
try {
  const grid = await loadGrid(server.url, 5, 5);
  const cells = connectedClearCells(grid, [0, 0], 1);
  const rand = rng(11);
  const pairs = [];
  while (pairs.length < N) {
    const a = cells[Math.floor(rand() * cells.length)], b = cells[Math.floor(rand() * cells.length)];
    if (Math.hypot(a[0] - b[0], a[1] - b[1]) >= 500) pairs.push([a, b]);
  }
  // The planners come from the server's registry: every one this map takes that plans at one
  // altitude (the pairs are free cells of the slice at 5 m). One request each first: a planner
  // answers 200, or 422 `timeout` when its per-grid preprocessing does not fit the server's
  // budget on this map (ch at 1 m on the city), which leaves it out of the load; anything else
  // fails.
  const registry = await (await fetch(`${server.url}api/planners`)).json();
  // Not the planners for small grids: the city at 1 m is too large for their tables.
  const candidates = registry.planners.filter((p) => p.available && p.dims === 2 && p.maps !== "small_grid").map((p) => p.name);
  check("the registry lists 2D planners for this map", candidates.length > 0, JSON.stringify(registry));
  const planners = [];
  for (const planner of candidates) {
    const res = await fetch(`${server.url}api/plan`, { method: "POST", headers: { "content-type": "application/json" },
      body: JSON.stringify({ planner, start_ne: pairs[0][0], goal_ne: pairs[0][1] }) });
    const json = await res.json();
    if (res.status === 200) planners.push(planner);
    else if (res.status === 422 && json.kind === "timeout") console.log(`left out of the load: ${planner} (${json.message})`);
    else check(`${planner} plans one request`, false, `${res.status} ${JSON.stringify(json).slice(0, 200)}`);
  }
  check("some planners plan on this map", planners.length > 0, JSON.stringify(candidates));
  console.log(`load mix: ${planners.join(", ")}`);
  const body = (i) => JSON.stringify({ planner: planners[i % planners.length], start_ne: pairs[i][0], goal_ne: pairs[i][1] });
  const rssBefore = vm(server.pid, "VmRSS");

  async function once(i) {
    const t0 = performance.now();
    try {
      const res = await fetch(`${server.url}api/plan`, { method: "POST", headers: { "content-type": "application/json" }, body: body(i) });
      const json = await res.json();
      return { status: res.status, ms: performance.now() - t0, json, retryAfter: res.headers.get("retry-after") };
    } catch (e) {
      return { status: 0, ms: performance.now() - t0, json: { message: String(e) } };
    }
  }

  // Phase 1: all at once, no retries.
  const t1 = performance.now();
  const first = await Promise.all(pairs.map((_, i) => once(i)));
  const wall1 = performance.now() - t1;
  const counts = {};
  for (const r of first) counts[r.status] = (counts[r.status] || 0) + 1;
  const bad = first.filter((r) => r.status !== 200 && r.status !== 503 && r.status !== 504);
  check(`${N} concurrent requests answered 200, 503 or 504`, bad.length === 0,
    bad.slice(0, 3).map((r) => `${r.status} ${JSON.stringify(r.json).slice(0, 200)}`).join(" | "));
  check("503s say busy, with Retry-After", first.filter((r) => r.status === 503)
    .every((r) => r.json.kind === "busy" && Number(r.retryAfter) >= 1));
  check("504s say queue_timeout or over_budget", first.filter((r) => r.status === 504)
    .every((r) => r.json.kind === "queue_timeout" || r.json.kind === "over_budget"));
  check("some requests were planned", (counts[200] || 0) > 0);
  const ok1 = first.filter((r) => r.status === 200).map((r) => r.ms);
  const all1 = first.map((r) => r.ms);
  console.log(`phase 1 (no retries, ${serveArgs.join(" ") || "default queue"}): ${JSON.stringify(counts)} in ${wall1.toFixed(0)} ms (${(1000 * ok1.length / wall1).toFixed(1)} plans/s); latency p50 ${pct(all1, 0.5).toFixed(1)} ms, p99 ${pct(all1, 0.99).toFixed(1)} ms (200s: p50 ${pct(ok1, 0.5).toFixed(1)} ms, p99 ${pct(ok1, 0.99).toFixed(1)} ms)`);
  // The server's counters agree with what the clients saw (a job past its budget may still run).
  const status = await (await fetch(`${server.url}api/status`)).json();
  console.log(`status after phase 1: ${JSON.stringify(status)}`);
  check("/api/status counts the 503s as rejected", status.rejected === (counts[503] || 0), JSON.stringify(status));
  check("/api/status counts the 504s as timeouts", status.queue_timeouts + status.over_budget === (counts[504] || 0), JSON.stringify(status));
  check("/api/status: nothing queued once all are answered", status.queued === 0, JSON.stringify(status));
  // Every pool job so far: the grid, one probe per candidate planner, and phase 1.
  const jobs = 1 + candidates.length + N;
  check("/api/status: every job served, rejected or timed out",
    status.served + status.rejected + status.queue_timeouts + status.over_budget === jobs, `${jobs} jobs: ${JSON.stringify(status)}`);

  // Phase 2: the same requests from clients that retry on 503 after a short pause.
  async function untilPlanned(i) {
    const t0 = performance.now();
    for (let attempt = 0; attempt < 2000; attempt++) {
      const r = await once(i);
      if (r.status !== 503) return { ...r, ms: performance.now() - t0, attempts: attempt + 1 };
      await new Promise((res) => setTimeout(res, 5 + rand() * 20));
    }
    return { status: 503, ms: performance.now() - t0 };
  }
  const t2 = performance.now();
  const second = await Promise.all(pairs.map((_, i) => untilPlanned(i)));
  const wall2 = performance.now() - t2;
  const notOk = second.filter((r) => r.status !== 200);
  check(`${N} retrying clients all planned (200)`, notOk.length === 0,
    notOk.slice(0, 3).map((r) => `${r.status} ${JSON.stringify(r.json).slice(0, 200)}`).join(" | "));
  const costs = second.filter((r) => r.status === 200).map((r) => r.json.cost_m);
  check("every route is at least its straight line", second.every((r) => r.status !== 200 || r.json.cost_m >= r.json.straight_line_m - 1e-6));
  const all2 = second.map((r) => r.ms);
  const plans = second.map((r) => r.json.timings_us ? r.json.timings_us.total_us / 1000 : 0);
  const hwm = vm(server.pid, "VmHWM");
  console.log(`phase 2 (retry on 503): ${second.length} planned in ${wall2.toFixed(0)} ms (${(1000 * second.length / wall2).toFixed(1)} plans/s); latency p50 ${pct(all2, 0.5).toFixed(1)} ms, p99 ${pct(all2, 0.99).toFixed(1)} ms; planning alone p50 ${pct(plans, 0.5).toFixed(1)} ms, p99 ${pct(plans, 0.99).toFixed(1)} ms; mean route ${(costs.reduce((a, b) => a + b, 0) / costs.length).toFixed(0)} m`);
  console.log(`server memory: RSS ${rssBefore.toFixed(1)} MiB after loading the map, peak (VmHWM) ${hwm.toFixed(1)} MiB`);
  check("peak RSS under 1 GiB", hwm < 1024, `${hwm} MiB`);
} finally {
  server.stop();
}
console.log(`load: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);

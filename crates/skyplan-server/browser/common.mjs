// Shared by the browser test and the load test: start `skyplan serve` on a free loopback port,
// read the map's grid, pick free points connected to each other.
import { spawn } from "node:child_process";
import net from "node:net";

export function freePort() {
  return new Promise((resolve, reject) => {
    const srv = net.createServer();
    srv.on("error", reject);
    srv.listen(0, "127.0.0.1", () => {
      const { port } = srv.address();
      srv.close(() => resolve(port));
    });
  });
}

/** Starts `bin serve --bind 127.0.0.1:PORT …`; resolves once it prints its address. */
export async function startServer(bin, extraArgs = []) {
  const port = await freePort();
  return startProcess(bin, ["serve", "--bind", `127.0.0.1:${port}`, ...extraArgs]);
}

/** Starts a program that prints `http://ADDR/` once it serves; resolves with that address. */
export async function startProcess(bin, args) {
  const proc = spawn(bin, args, {
    stdio: ["ignore", "pipe", "inherit"],
  });
  const url = await new Promise((resolve, reject) => {
    let out = "";
    const timer = setTimeout(() => reject(new Error(`${bin} printed no address in 20 s: ${out}`)), 20000);
    proc.stdout.on("data", (d) => {
      out += d;
      const m = out.match(/http:\/\/[0-9.:]+\//);
      if (m) {
        clearTimeout(timer);
        resolve(m[0]);
      }
    });
    proc.on("exit", (code) => reject(new Error(`${bin} exited with ${code}: ${out}`)));
  });
  proc.stdout.resume();
  return { url, proc, pid: proc.pid, stop: () => proc.kill("SIGTERM") };
}

/** The grid at an altitude and margin, decoded: blocked[row][col], row 0 the southern edge. */
export async function loadGrid(url, alt_m, safety_m) {
  const res = await fetch(`${url}api/map?alt_m=${alt_m}&safety_m=${safety_m}&cell_m=1`);
  if (!res.ok) throw new Error(`GET /api/map: ${res.status}`);
  const map = await res.json();
  const g = map.grid;
  const blocked = g.runs.map((runs) => {
    const row = new Uint8Array(g.cols);
    let c = 0, b = false;
    for (const len of runs) {
      if (b) row.fill(1, c, c + len);
      c += len;
      b = !b;
    }
    return row;
  });
  return { map, g, blocked };
}

/** Cells free with `clearance` free cells all round, connected to the cell nearest `fromNe`. */
export function connectedClearCells({ g, blocked }, fromNe, clearance) {
  const clear = (r, c) => {
    for (let dr = -clearance; dr <= clearance; dr++)
      for (let dc = -clearance; dc <= clearance; dc++) {
        const rr = r + dr, cc = c + dc;
        if (rr < 0 || cc < 0 || rr >= g.rows || cc >= g.cols || blocked[rr][cc]) return false;
      }
    return true;
  };
  const r0 = Math.floor((fromNe[0] - g.origin_north_m) / g.cell_m);
  const c0 = Math.floor((fromNe[1] - g.origin_east_m) / g.cell_m);
  const seen = new Uint8Array(g.rows * g.cols);
  const queue = [[r0, c0]];
  seen[r0 * g.cols + c0] = 1;
  const out = [];
  while (queue.length) {
    const [r, c] = queue.pop();
    if (clear(r, c)) out.push([g.origin_north_m + (r + 0.5) * g.cell_m, g.origin_east_m + (c + 0.5) * g.cell_m]);
    for (const [dr, dc] of [[1, 0], [-1, 0], [0, 1], [0, -1]]) {
      const rr = r + dr, cc = c + dc;
      if (rr < 0 || cc < 0 || rr >= g.rows || cc >= g.cols) continue;
      const k = rr * g.cols + cc;
      if (seen[k] || blocked[rr][cc]) continue;
      seen[k] = 1;
      queue.push([rr, cc]);
    }
  }
  return out;
}

/** A small seeded generator (mulberry32), so runs are repeatable. */
export function rng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

export function nearest(cells, ne) {
  let best = null, bd = Infinity;
  for (const p of cells) {
    const d = (p[0] - ne[0]) ** 2 + (p[1] - ne[1]) ** 2;
    if (d < bd) { bd = d; best = p; }
  }
  return best;
}

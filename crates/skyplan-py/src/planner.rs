//! `Planner`: one world loaded once, planned on by the planning API's sessions; `Plan`: its
//! answer as numpy arrays and a dict.

use crate::arrays::{blocked2, describe, float_pair, to_json};
use crate::errors::{bad_input, to_py};
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use serde_json::{Map, Value};
use skyplan_cspace::{Grid2, GridFrame};
use skyplan_export::Format;
use skyplan_plan::{
    MapFileError, MapFileOptions, MapKinds, Optimality, PlanFailure, PlanRequest, PlannerId,
    Session, World,
};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A file's error as the matching `OSError`, naming the file.
fn io_error(path: &Path, e: std::io::Error) -> PyErr {
    let message = format!("{}: {e}", path.display());
    match e.kind() {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// A map file by its extension, as the CLI's `--map` reads it.
fn load_file(path: &Path, resolution_m: Option<f64>, unknown_free: bool) -> PyResult<World> {
    let name = path.display().to_string();
    let options = MapFileOptions {
        resolution_m,
        unknown_free,
        ..Default::default()
    };
    World::load_file(path, &options, |p| std::fs::read(p).map_err(|e| io_error(p, e))).map_err(
        |e| match e {
            MapFileError::UnknownType => bad_input(format!(
                "{name}: unknown map type; expected .csv (FCND colliders), .yaml (map_server), .png/.pgm (with resolution_m=) or .map (MovingAI)"
            )),
            MapFileError::NeedsResolution => bad_input(format!(
                "{name}: a bare image needs resolution_m= (metres per pixel), or use a map_server .yaml"
            )),
            MapFileError::ResolutionNotTaken => bad_input(
                "resolution_m: only bare .png/.pgm maps take it (a .yaml map gives its own; other maps are in metres)",
            ),
            MapFileError::Read { error, .. } => error,
            MapFileError::Map(failure) => to_py(failure),
        },
    )
}

/// A numpy occupancy grid (row 0 the southern edge, nonzero = blocked) as a world.
fn grid_world(grid: &Bound<'_, PyAny>, origin_ne: [f64; 2], cell_m: f64) -> PyResult<World> {
    let (rows, cols, blocked) = blocked2(grid, "map")?;
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(bad_input(format!(
            "cell_m {cell_m}: expected a size above 0"
        )));
    }
    let too_large = || bad_input(format!("map: a {rows} × {cols} grid is too large"));
    let frame = GridFrame {
        origin_north_m: origin_ne[0],
        origin_east_m: origin_ne[1],
        cell_m,
    };
    let grid = Grid2::new(
        u32::try_from(rows).map_err(|_| too_large())?,
        u32::try_from(cols).map_err(|_| too_large())?,
        blocked,
        frame,
    )
    .map_err(|e| bad_input(format!("map: {e}")))?;
    Ok(World::from_grid(&format!("numpy grid {rows}x{cols}"), grid))
}

/// A JSON value as a Python object (through the `json` module).
pub(crate) fn json_to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| to_py(PlanFailure::internal(format!("JSON: {e}"))))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// One registry row as a dict, in the registry's field order: the planner's `info()` fields,
/// then the predicates tests and clients choose planners by.
fn planner_row(py: Python<'_>, planner: PlannerId) -> PyResult<Bound<'_, PyDict>> {
    let info = planner.info();
    // The enums' names as `--json` spells them (`asymptotically_optimal`).
    let json = serde_json::to_value(info)
        .map_err(|e| to_py(PlanFailure::internal(format!("JSON: {e}"))))?;
    let name_of = |field: &str| {
        json.get(field).and_then(Value::as_str).ok_or_else(|| {
            to_py(PlanFailure::internal(format!(
                "registry: {field} is not a name"
            )))
        })
    };
    let row = PyDict::new(py);
    row.set_item("name", info.name)?;
    row.set_item("label", info.label)?;
    row.set_item("dims", info.dims)?;
    row.set_item("optimality", name_of("optimality")?)?;
    row.set_item("maps", name_of("maps")?)?;
    row.set_item("summary", info.summary)?;
    row.set_item("exact", info.optimality == Optimality::Exact)?;
    row.set_item("grid_path", planner.is_cell_planner())?;
    row.set_item("needs_obstacles", info.maps == MapKinds::Obstacles)?;
    Ok(row)
}

/// Every planner there is, in registry order: a list of dicts, one per planner, generated from
/// the planning API's registry (a new planner appears here without any edit in Python).
///
/// Each dict: `name` (the `planner=` value), `label`, `dims` (2: routes at one altitude, 3:
/// routes that climb), `optimality` (`exact`, `exact_for_objective`, `any_angle`,
/// `exact_any_angle`, `feasible`, `asymptotically_optimal`), `maps` (`any_grid`,
/// `obstacles`, or `small_grid`: any grid small enough for the planner's per-grid table),
/// `summary` (one line), and three predicates: `exact` (the shortest grid
/// path under the move model: its cost equals Dijkstra's), `grid_path` (it searches grid cells
/// and takes the grid-path options `connectivity`, `corner_cutting`, `prune`, `epsilon`,
/// `shortcut`; its route is that cell path unless its optimality is `any_angle`),
/// `needs_obstacles` (it needs a map of obstacles: FCND colliders or footprints, not a fixed
/// grid).
#[pyfunction]
pub fn planners(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let rows = PlannerId::ALL
        .iter()
        .map(|&p| planner_row(py, p))
        .collect::<PyResult<Vec<_>>>()?;
    PyList::new(py, rows)
}

/// A map loaded once, and every skyplan planner on it (`skyplan.planners()` lists them).
///
/// `map`: `None` for the bundled FCND city; a path (str or `os.PathLike`) to an FCND
/// `colliders.csv`, a ROS map_server `.yaml`, a bare `.png`/`.pgm` image (with `resolution_m=`)
/// or a MovingAI `.map`; or a 2-D numpy array (nonzero = blocked, row 0 the southern edge, as
/// `create_grid` makes it), placed by `origin_ne=(north_m, east_m)` of its corner (for an FCND
/// grid, `(north_offset, east_offset)`) and `cell_m=` (1).
///
/// `home=(lat_deg, lon_deg)` gives a map without a geodetic home one (colliders maps carry
/// their own): waypoints then get lat/lon and `to_file` works. `unknown_free=True` reads an
/// image's unknown pixels as free. `terrain=` a DEM (GeoTIFF or SRTM `.hgt`) under a map with a
/// home: `plan(..., alt_agl_m=H)` then keeps H metres above the ground all along the route, and
/// `lla` gains a third column, the height above mean sea level.
///
/// A `Planner` may be shared between threads: each concurrent `plan` gets its own session of
/// the planning API (grids, roadmaps and sessions are kept for the next calls), and the GIL is
/// released while planning.
#[pyclass(module = "skyplan", frozen)]
pub struct Planner {
    world: World,
    idle: Mutex<Vec<Session>>,
}

/// A plan request from `plan`'s arguments: `start`/`goal` as `(north_m, east_m)` and every
/// other keyword a planning option.
pub(crate) fn request_of(
    start: Option<&Bound<'_, PyAny>>,
    goal: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PlanRequest> {
    let mut fields = Map::new();
    if let Some(opts) = options {
        for (k, v) in opts.iter() {
            let key: String = k.extract()?;
            let value = to_json(&v, &key)?;
            fields.insert(key, value);
        }
    }
    for (which, given) in [("start", start), ("goal", goal)] {
        let Some(point) = given.filter(|p| !p.is_none()) else {
            continue;
        };
        if fields.contains_key(&format!("{which}_ne"))
            || fields.contains_key(&format!("{which}_lla"))
        {
            return Err(bad_input(format!(
                "{which}: given twice (positionally and as {which}_ne= or {which}_lla=)"
            )));
        }
        let [n, e] = float_pair(point, which)?;
        fields.insert(format!("{which}_ne"), serde_json::json!([n, e]));
    }
    // The option named on errors (`alt_m: invalid type: …`), as the HTTP API does.
    serde_path_to_error::deserialize(Value::Object(fields)).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        if path == "." || path.is_empty() {
            bad_input(format!("options: {inner}"))
        } else {
            bad_input(format!("{path}: {inner}"))
        }
    })
}

impl Planner {
    /// Runs `job` on one of the planner's sessions with the GIL released; a panic is a
    /// `PlanError` (its session dropped).
    pub(crate) fn with_session<T: Send>(
        &self,
        py: Python<'_>,
        job: impl FnOnce(&mut Session) -> T + Send,
    ) -> PyResult<T> {
        let mut session = self.take_session();
        let outcome = py.detach(|| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job(&mut session)))
                .map(|result| (result, session))
        });
        match outcome {
            Ok((result, session)) => {
                self.give_back(session);
                Ok(result)
            }
            // A panic is a bug: its session is dropped, and Python gets a PlanError.
            Err(_) => Err(to_py(PlanFailure::internal(
                "internal error while planning (a panic); please report this with the request",
            ))),
        }
    }

    /// The planner's world.
    pub(crate) fn world(&self) -> &World {
        &self.world
    }

    fn take_session(&self) -> Session {
        let mut idle = self.idle.lock().unwrap_or_else(|p| p.into_inner());
        idle.pop()
            .unwrap_or_else(|| Session::new(self.world.clone()))
    }

    fn give_back(&self, session: Session) {
        let mut idle = self.idle.lock().unwrap_or_else(|p| p.into_inner());
        idle.push(session);
    }
}

#[pymethods]
impl Planner {
    #[new]
    #[pyo3(signature = (map = None, *, home = None, resolution_m = None, unknown_free = false, origin_ne = None, cell_m = None, terrain = None))]
    fn new(
        map: Option<&Bound<'_, PyAny>>,
        home: Option<&Bound<'_, PyAny>>,
        resolution_m: Option<f64>,
        unknown_free: bool,
        origin_ne: Option<&Bound<'_, PyAny>>,
        cell_m: Option<f64>,
        terrain: Option<PathBuf>,
    ) -> PyResult<Self> {
        let is_path = map.is_some_and(|m| {
            m.is_instance_of::<PyString>() || m.hasattr("__fspath__").unwrap_or(false)
        });
        if !map.is_some_and(|m| !is_path && !m.is_none())
            && (origin_ne.is_some() || cell_m.is_some())
        {
            return Err(bad_input(
                "origin_ne, cell_m: only a numpy grid map takes them (files carry their own placement)",
            ));
        }
        let world = match map {
            None => World::fcnd_city(),
            Some(m) if m.is_none() => World::fcnd_city(),
            Some(m) if is_path => {
                let path: PathBuf = m
                    .extract()
                    .map_err(|_| bad_input(format!("map: expected a path, got {}", describe(m))))?;
                load_file(&path, resolution_m, unknown_free)?
            }
            Some(m) => {
                let origin = match origin_ne {
                    Some(o) => float_pair(o, "origin_ne")?,
                    None => [0.0, 0.0],
                };
                grid_world(m, origin, cell_m.unwrap_or(1.0))?
            }
        };
        let world = match home {
            Some(h) => {
                let [lat, lon] = float_pair(h, "home")?;
                world.with_home(lat, lon).map_err(to_py)?
            }
            None => world,
        };
        let world = match terrain {
            Some(path) => {
                let name = path.display().to_string();
                // Bounded before reading, as the CLI does.
                if let Ok(meta) = std::fs::metadata(&path)
                    && meta.len() > skyplan_map::terrain::MAX_DEM_BYTES
                {
                    return Err(bad_input(format!(
                        "{name}: {} bytes is more than a DEM of {} samples can hold; crop it",
                        meta.len(),
                        skyplan_map::terrain::MAX_DEM_SAMPLES
                    )));
                }
                let bytes = std::fs::read(&path).map_err(|e| io_error(&path, e))?;
                let dem = skyplan_map::terrain::parse_dem(&name, &bytes)
                    .map_err(|e| bad_input(format!("{name}: {e}")))?;
                world.with_terrain(&name, dem).map_err(to_py)?
            }
            None => world,
        };
        Ok(Self {
            world,
            idle: Mutex::new(Vec::new()),
        })
    }

    /// The map's name (its path, or the bundled map's).
    #[getter]
    fn name(&self) -> String {
        self.world.name().to_string()
    }

    /// What the map was loaded from: `colliders`, `image`, `moving_ai`, `random` or `grid`.
    #[getter]
    fn kind(&self) -> String {
        serde_json::to_value(self.world.kind())
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default()
    }

    /// The horizontal extent every planner accepts at 1 m cells:
    /// `(north_min_m, north_max_m, east_min_m, east_max_m)`.
    #[getter]
    fn bounds_ne(&self) -> (f64, f64, f64, f64) {
        let b = self.world.bounds_ne(1.0);
        (b.north_min_m, b.north_max_m, b.east_min_m, b.east_max_m)
    }

    /// Plans a route.
    ///
    /// `start`, `goal`: `(north_m, east_m)` of the map's local frame (the map's defaults when
    /// left out: on the bundled city the home and a far street corner). Geodetic positions go
    /// as `start_lla=(lat, lon)` / `goal_lla=(lat, lon)`. Every other keyword is a planning
    /// option, named as the CLI's long options with underscores: `planner` (a `name` from
    /// `skyplan.planners()`, which lists every planner and what it does),
    /// `alt_m`, `safety_m`, `cell_m`, `start_alt_m`, `goal_alt_m`, `time_limit_ms`, `seed`,
    /// `connectivity`, `corner_cutting`, … — unknown names and options the planner does not use
    /// raise `skyplan.BadInput`.
    ///
    /// Raises `InvalidStart`, `InvalidGoal`, `NoPath`, `Timeout` or `BadInput` (all
    /// `skyplan.PlanError`s) with the planning API's message.
    #[pyo3(signature = (start = None, goal = None, **options))]
    fn plan(
        &self,
        py: Python<'_>,
        start: Option<&Bound<'_, PyAny>>,
        goal: Option<&Bound<'_, PyAny>>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Plan> {
        let request = request_of(start, goal, options)?;
        let result = self.with_session(py, move |session| session.plan(&request))?;
        result.map(|inner| Plan { inner }).map_err(to_py)
    }

    fn __repr__(&self) -> String {
        format!("skyplan.Planner({:?})", self.world.name())
    }
}

/// A planned route: every segment re-checked against the map.
///
/// `waypoints`: (n, 4) float64 `[north_m, east_m, alt_m, heading_rad]` (FCND's waypoint
/// layout); `lla`: (n, 2) `[lat_deg, lon_deg]` or None on maps without a geodetic home;
/// `cost_m`; `stats`: everything else the planner reports, as a dict.
#[pyclass(module = "skyplan", frozen)]
pub struct Plan {
    pub(crate) inner: skyplan_plan::Plan,
}

#[pymethods]
impl Plan {
    /// (n, 4) float64 array: `[north_m, east_m, alt_m, heading_rad]` per waypoint.
    #[getter]
    fn waypoints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let w = &self.inner.waypoints;
        let flat: Vec<f64> = w.iter().flatten().copied().collect();
        let a = Array2::from_shape_vec((w.len(), 4), flat)
            .map_err(|e| to_py(PlanFailure::internal(format!("waypoints: {e}"))))?;
        Ok(numpy::IntoPyArray::into_pyarray(a, py))
    }

    /// (n, 2) float64 array of `[lat_deg, lon_deg]` (over terrain (n, 3), with `alt_amsl_m`), or
    /// None (map without a geodetic home).
    #[getter]
    fn lla<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        let Some(ll) = &self.inner.waypoints_lla else {
            return Ok(None);
        };
        let width = ll.first().map_or(2, Vec::len);
        let flat: Vec<f64> = ll.iter().flatten().copied().collect();
        let a = Array2::from_shape_vec((ll.len(), width), flat)
            .map_err(|e| to_py(PlanFailure::internal(format!("lla: {e}"))))?;
        Ok(Some(numpy::IntoPyArray::into_pyarray(a, py)))
    }

    /// (n, 11) float64 array of the trajectory's samples (`trajectory=True`), rows `[t_s,
    /// north_m, east_m, alt_m, v_north, v_east, v_up, a_north, a_east, a_up, yaw_deg]` at
    /// `sample_hz`; None without a trajectory. Its method, pieces and proven bounds are in
    /// `stats["trajectory"]`.
    #[getter]
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        let Some(t) = &self.inner.trajectory else {
            return Ok(None);
        };
        let flat: Vec<f64> = t.samples.iter().flatten().copied().collect();
        let a = Array2::from_shape_vec((t.samples.len(), 11), flat)
            .map_err(|e| to_py(PlanFailure::internal(format!("trajectory: {e}"))))?;
        Ok(Some(numpy::IntoPyArray::into_pyarray(a, py)))
    }

    /// The planner's route length, metres (octile cost of a grid path; Euclidean length of
    /// any-angle, roadmap and 3D routes).
    #[getter]
    fn cost_m(&self) -> f64 {
        self.inner.cost_m
    }

    /// The planner that made the route (CLI spelling).
    #[getter]
    fn planner(&self) -> &'static str {
        self.inner.planner.name()
    }

    /// Everything the planner reports besides the waypoints (map, grid, start, goal, cost,
    /// expansions, timings in microseconds, planner details) — the CLI's `--json` fields.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut value = serde_json::to_value(&self.inner)
            .map_err(|e| to_py(PlanFailure::internal(format!("JSON: {e}"))))?;
        if let Some(obj) = value.as_object_mut() {
            obj.remove("waypoints");
            obj.remove("waypoints_lla");
            if let Some(t) = obj.get_mut("trajectory").and_then(|t| t.as_object_mut()) {
                t.remove("samples"); // the `trajectory` array
            }
        }
        json_to_py(py, &value)
    }

    /// The whole plan as JSON text (the CLI's `plan --json` document without its `outputs`).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner)
            .map_err(|e| to_py(PlanFailure::internal(format!("JSON: {e}"))))
    }

    /// Writes the waypoints to `path` in the format its extension names, as the CLI's `--out`:
    /// `.json`, `.csv`, `.h5`/`.hdf5` (FCND's `data` dataset), `.geojson`, `.plan`
    /// (QGroundControl); `format=` overrides the extension. Needs a map with a geodetic home.
    #[pyo3(signature = (path, format = None))]
    fn to_file(&self, path: PathBuf, format: Option<&str>) -> PyResult<()> {
        let format = match format {
            Some(name) => Format::from_name(name).ok_or_else(|| {
                bad_input(format!("format: expected json, csv, hdf5, geojson or plan, got {name:?}"))
            })?,
            None => Format::from_path(&path).ok_or_else(|| {
                bad_input(format!(
                    "{}: cannot tell the format from the extension; use .json .csv .h5 .geojson .plan or format=",
                    path.display()
                ))
            })?,
        };
        let mission = self.inner.mission.as_ref().ok_or_else(|| {
            bad_input(format!(
                "{}: waypoint files carry lat/lon; {} has no geodetic home: Planner(..., home=(lat, lon))",
                path.display(),
                self.inner.map
            ))
        })?;
        let summary = serde_json::json!({
            "map": self.inner.map,
            "planner": self.inner.planner,
            "cost_m": self.inner.cost_m,
        });
        let bytes = skyplan_export::encode(format, mission, &summary)
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        std::fs::write(&path, bytes).map_err(|e| io_error(&path, e))
    }

    fn __len__(&self) -> usize {
        self.inner.waypoints.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "skyplan.Plan(planner={:?}, waypoints={}, cost_m={:.2})",
            self.inner.planner.name(),
            self.inner.waypoints.len(),
            self.inner.cost_m
        )
    }
}

//! [`World`]: one loaded map of any kind, with one set of bounds for every planner family.

use crate::failure::PlanFailure;
use crate::request::{PlanRequest, Resolved};
use skyplan_cspace::{Cell, Grid2};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_imagemap::MapYaml;
use skyplan_map::colliders::{CollidersMap, GeodeticHome};
use skyplan_map::footprints::{DEFAULT_HEIGHT_M, FootprintMap, GeoFootprints};
use skyplan_map::terrain::{Dem, Terrain};
use std::sync::Arc;

/// The FCND city map (Udacity FCND-Motion-Planning `colliders.csv`), compiled in.
pub const FCND_CITY_CSV: &str = include_str!("../../../data/colliders.csv");
/// How the bundled map is named in messages and outputs.
pub const FCND_CITY_NAME: &str = "colliders.csv (bundled FCND city map)";
/// The default goal on the bundled map: a free street corner across the city from the home.
pub const FCND_DEFAULT_GOAL_NE: [f64; 2] = [420.0, 390.0];

/// Resource limits checked before anything large is allocated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Most memory one world or request may need, bytes (estimated before allocating).
    pub max_memory_bytes: u64,
}

impl Default for Limits {
    /// 8 GiB.
    fn default() -> Self {
        Self {
            max_memory_bytes: 8 << 30,
        }
    }
}

/// Bytes as people read them (`1.5 GB`).
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.0} MB", b / 1e6)
    } else {
        format!("{:.0} kB", b / 1e3)
    }
}

/// Refuses an estimate above the limit, naming what needs the memory and what to change.
pub(crate) fn check_memory(
    estimate: u64,
    limits: &Limits,
    what: &str,
    change: &str,
) -> Result<(), PlanFailure> {
    if estimate <= limits.max_memory_bytes {
        return Ok(());
    }
    Err(PlanFailure::bad_request(format!(
        "{what} needs about {} of memory, above the limit of {}; {change}, or raise the limit (max_memory)",
        human_bytes(estimate),
        human_bytes(limits.max_memory_bytes)
    )))
}

/// What a world was loaded from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MapKind {
    /// FCND `colliders.csv`: boxes in metres about a geodetic home.
    Colliders,
    /// An occupancy image (PNG/PGM, bare or through a ROS map_server YAML).
    Image,
    /// A MovingAI `.map` grid.
    MovingAi,
    /// A random workspace.
    Random,
    /// A grid given directly.
    Grid,
    /// GeoJSON building footprints: polygons with holes and height bands, projected about a home.
    Footprints,
}

/// A map file's format, told by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFormat {
    /// `.csv`: FCND colliders ([`World::from_colliders_csv`]).
    Colliders,
    /// `.yaml`, `.yml`: a ROS map_server description of an image ([`MapYaml`]).
    MapServer,
    /// `.png`, `.pgm`: a bare occupancy image ([`MapYaml::bare`]).
    Image,
    /// `.map`: a MovingAI grid ([`World::from_movingai`]).
    MovingAi,
    /// `.geojson`: building footprints ([`World::from_geojson`]).
    GeoJson,
    /// `.osm`: OpenStreetMap XML, its buildings ([`World::from_osm`]).
    Osm,
    /// `.osm.pbf` (any `.pbf`): OpenStreetMap PBF, its buildings ([`World::from_osm`]).
    OsmPbf,
}

impl MapFormat {
    /// The format of `path` by its extension (any case), or `None` for another extension.
    pub fn of_path(path: &std::path::Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "csv" => Self::Colliders,
            "yaml" | "yml" => Self::MapServer,
            "png" | "pgm" => Self::Image,
            "map" => Self::MovingAi,
            "geojson" => Self::GeoJson,
            "osm" => Self::Osm,
            "pbf" => Self::OsmPbf,
            _ => return None,
        })
    }
}

#[derive(Debug, Clone)]
pub(crate) enum Source {
    Colliders(Arc<CollidersMap>),
    Grid(Arc<Grid2>),
    Footprints(Arc<Footprints>),
}

/// A footprint map: as parsed (longitude/latitude, kept to project about another home) and in
/// the local frame.
#[derive(Debug, Clone)]
pub(crate) struct Footprints {
    pub(crate) geo: Arc<GeoFootprints>,
    pub(crate) local: FootprintMap,
    /// Buildings of an OpenStreetMap file that could not be made, each `"way 12: why"`.
    pub(crate) skipped: Arc<Vec<String>>,
}

/// Horizontal extent shared by every planner family, metres north/east of the map's origin.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct BoundsNe {
    /// Southern edge.
    pub north_min_m: f64,
    /// Northern edge.
    pub north_max_m: f64,
    /// Western edge.
    pub east_min_m: f64,
    /// Eastern edge.
    pub east_max_m: f64,
}

impl BoundsNe {
    /// Whether the point lies inside (edges included).
    pub fn contains(&self, north_m: f64, east_m: f64) -> bool {
        (self.north_min_m..=self.north_max_m).contains(&north_m)
            && (self.east_min_m..=self.east_max_m).contains(&east_m)
    }
}

impl std::fmt::Display for BoundsNe {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "north {:.2}..{:.2} m, east {:.2}..{:.2} m",
            self.north_min_m, self.north_max_m, self.east_min_m, self.east_max_m
        )
    }
}

/// One loaded map: colliders boxes, an image, a MovingAI grid or a random workspace, with its
/// geodetic home when it has one. Built from text or bytes (no I/O).
///
/// ```
/// use skyplan_plan::{World, MapKind};
/// let world = World::fcnd_city();
/// assert_eq!(world.kind(), MapKind::Colliders);
/// assert_eq!(world.colliders().map(|m| m.boxes.len()), Some(3845));
/// let b = world.bounds_ne(1.0);
/// assert!(b.contains(-316.0, -389.0)); // the grid's corner: every planner takes it
/// ```
#[derive(Debug, Clone)]
pub struct World {
    name: String,
    kind: MapKind,
    pub(crate) source: Source,
    frame: Option<LocalFrame>,
    pub(crate) default_start_ne: Option<[f64; 2]>,
    pub(crate) default_goal_ne: Option<[f64; 2]>,
    /// The ground under the map, placed about its home (`with_terrain`).
    terrain: Option<Arc<Terrain>>,
}

fn parse_failure(name: &str, e: impl std::fmt::Display) -> PlanFailure {
    PlanFailure::bad_request(format!("{name}: {e}"))
}

fn frame_at(lat_deg: f64, lon_deg: f64, what: &str) -> Result<LocalFrame, PlanFailure> {
    LocalFrame::new(Lla {
        lat_deg,
        lon_deg,
        alt_m: 0.0,
    })
    .map_err(|e| PlanFailure::bad_request(format!("{what}: {e}")))
}

impl World {
    /// Cells of the grid at this cell size (before building it), saturating; the map's own
    /// grid's cells for image, MovingAI and random maps.
    pub fn cells_at(&self, cell_m: f64) -> u64 {
        if let Some(g) = self.fixed_grid() {
            return g.len() as u64;
        }
        let b = self.bounds_ne(cell_m);
        let rows = ((b.north_max_m - b.north_min_m) / cell_m).ceil();
        let cols = ((b.east_max_m - b.east_min_m) / cell_m).ceil();
        let cells = rows * cols;
        if cells.is_finite() && cells < 1.8e19 {
            cells as u64
        } else {
            u64::MAX
        }
    }

    /// What `request`'s planner would build on this world, estimated before anything is
    /// allocated (the estimate a session checks against its memory limit): how many units and
    /// what they are (`cells` of its grid, `voxels` of its lattice), or `None` for a planner
    /// whose memory does not grow with the map. A bad request is refused as a plan is.
    ///
    /// ```
    /// use skyplan_plan::{PlanRequest, PlannerId, World};
    /// let city = World::fcnd_city();
    /// let (cells, what) = city.estimate(&PlanRequest::default())?.unwrap();
    /// assert_eq!((cells, what), (921 * 921, "cells"));
    /// let voxel = PlanRequest { planner: Some(PlannerId::Voxel), voxel_m: Some(10.0), ..Default::default() };
    /// assert_eq!(city.estimate(&voxel)?.map(|e| e.1), Some("voxels"));
    /// # Ok::<(), skyplan_plan::PlanFailure>(())
    /// ```
    pub fn estimate(
        &self,
        request: &PlanRequest,
    ) -> Result<Option<(u64, &'static str)>, PlanFailure> {
        let r = Resolved::new(request)?;
        Ok(r.planner
            .algorithm()
            .memory(self, &r)
            .map(|m| (m.units, m.what)))
    }

    fn grid_world(name: String, kind: MapKind, grid: Grid2) -> Self {
        Self {
            name,
            kind,
            source: Source::Grid(Arc::new(grid)),
            frame: None,
            default_start_ne: None,
            default_goal_ne: None,
            terrain: None,
        }
    }

    /// The bundled FCND city map, with its default start (the home) and goal.
    pub fn fcnd_city() -> Self {
        // The bundled text is pinned by tests; a failure here is a build defect.
        let mut world = Self::from_colliders_csv(FCND_CITY_NAME, FCND_CITY_CSV)
            .unwrap_or_else(|e| panic!("the bundled map does not parse: {e}"));
        world.default_goal_ne = Some(FCND_DEFAULT_GOAL_NE);
        world
    }

    /// An FCND colliders map from its text; `name` is used in messages. The default start is
    /// the home; the bundled map's own text (read from a file, say) also gets its default goal.
    ///
    /// ```
    /// use skyplan_plan::{World, FCND_CITY_CSV};
    /// let world = World::from_colliders_csv("colliders.csv", FCND_CITY_CSV)?;
    /// assert_eq!(world.default_endpoints_ne(), World::fcnd_city().default_endpoints_ne());
    /// # Ok::<(), skyplan_plan::PlanFailure>(())
    /// ```
    pub fn from_colliders_csv(name: &str, text: &str) -> Result<Self, PlanFailure> {
        let map =
            skyplan_map::colliders::parse_colliders(text).map_err(|e| parse_failure(name, e))?;
        let mut world = Self::from_colliders(name, map)?;
        if text.replace("\r\n", "\n") == FCND_CITY_CSV.replace("\r\n", "\n") {
            world.default_goal_ne = Some(FCND_DEFAULT_GOAL_NE);
        }
        Ok(world)
    }

    /// An FCND colliders map already parsed.
    pub fn from_colliders(name: &str, map: CollidersMap) -> Result<Self, PlanFailure> {
        if map.boxes.is_empty() {
            return Err(PlanFailure::bad_request(format!(
                "{name}: the map has no obstacle boxes (expected lines posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ after the header)"
            )));
        }
        let frame = frame_at(map.home.lat_deg, map.home.lon_deg, &format!("{name}: home"))?;
        Ok(Self {
            name: name.to_string(),
            kind: MapKind::Colliders,
            source: Source::Colliders(Arc::new(map)),
            frame: Some(frame),
            default_start_ne: Some([0.0, 0.0]),
            default_goal_ne: None,
            terrain: None,
        })
    }

    /// Building footprints from GeoJSON bytes ([`skyplan_map::footprints`]: a
    /// `FeatureCollection` of `Polygon`/`MultiPolygon` features with heights), projected to
    /// local metres about `home_lat_lon` (default: the centre of the data's bounding box), which
    /// becomes the map's geodetic home; buildings without a height get
    /// [`DEFAULT_HEIGHT_M`] (how many: [`FootprintMap::default_heights`]). The grid planners
    /// plan on it at the flight altitude ([`Grid2::from_footprints`](skyplan_cspace::Grid2::from_footprints));
    /// the 3D planners, which need boxes, refuse it. The default start is the home.
    ///
    /// ```
    /// use skyplan_plan::{MapKind, World};
    /// let text = br#"{"type": "FeatureCollection", "features": [{"type": "Feature",
    ///   "properties": {"height": 30}, "geometry": {"type": "Polygon", "coordinates":
    ///   [[[-122.3975, 37.7925], [-122.3970, 37.7925], [-122.3970, 37.7930], [-122.3975, 37.7925]]]}}]}"#;
    /// let world = World::from_geojson("one.geojson", text, None)?;
    /// assert_eq!(world.kind(), MapKind::Footprints);
    /// assert_eq!(world.obstacle_count(), Some(1));
    /// assert_eq!(world.footprints().map(|f| f.default_heights), Some(0));
    /// let home = world.frame().unwrap().home();
    /// assert!((home.lat_deg - 37.79275).abs() < 1e-9);
    /// let bad = World::from_geojson("bad.geojson", b"{}", None).unwrap_err();
    /// assert!(bad.message.starts_with("bad.geojson: type: expected \"FeatureCollection\""), "{}", bad.message);
    /// # Ok::<(), skyplan_plan::PlanFailure>(())
    /// ```
    pub fn from_geojson(
        name: &str,
        bytes: &[u8],
        home_lat_lon: Option<[f64; 2]>,
    ) -> Result<Self, PlanFailure> {
        let geo = skyplan_map::footprints::parse_geojson_bytes(bytes, DEFAULT_HEIGHT_M)
            .map_err(|e| parse_failure(name, e))?;
        Self::from_geo(name, geo, Vec::new(), home_lat_lon)
    }

    /// The buildings of an OpenStreetMap file ([`skyplan_map::osm`]: closed ways and
    /// multipolygon relations tagged `building`), XML (`pbf` false) or PBF bytes, as
    /// [`World::from_geojson`] makes a map of GeoJSON footprints: the same buildings give the
    /// same map. Buildings that cannot be made (an extract cut through them, a broken outline)
    /// are left out and named in [`World::notes`].
    ///
    /// ```
    /// use skyplan_plan::{MapKind, World};
    /// let text = br#"<osm version="0.6">
    ///   <node id="1" lat="60.1700" lon="24.9400"/> <node id="2" lat="60.1700" lon="24.9402"/>
    ///   <node id="3" lat="60.1701" lon="24.9402"/>
    ///   <way id="10"><nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="1"/><tag k="building" v="yes"/></way>
    ///   <way id="11"><nd ref="1"/><nd ref="2"/><tag k="building" v="yes"/></way>
    /// </osm>"#;
    /// let world = World::from_osm("two.osm", text, None, false)?;
    /// assert_eq!(world.kind(), MapKind::Footprints);
    /// assert_eq!(world.obstacle_count(), Some(1));
    /// assert_eq!(world.notes(), [
    ///     "1 of 1 buildings at the default height 10 m (no height or building:levels)",
    ///     "1 building skipped: way 11: the way is not closed (its last node is not its first)",
    /// ]);
    /// # Ok::<(), skyplan_plan::PlanFailure>(())
    /// ```
    pub fn from_osm(
        name: &str,
        bytes: &[u8],
        home_lat_lon: Option<[f64; 2]>,
        pbf: bool,
    ) -> Result<Self, PlanFailure> {
        let parsed = if pbf {
            skyplan_map::osm::parse_osm_pbf(bytes, DEFAULT_HEIGHT_M)
        } else {
            let text = std::str::from_utf8(bytes).map_err(|e| {
                PlanFailure::bad_request(format!(
                    "{name}: expected XML text, found bytes that are not UTF-8 ({e})"
                ))
            })?;
            skyplan_map::osm::parse_osm_xml(text, DEFAULT_HEIGHT_M)
        }
        .map_err(|e| parse_failure(name, e))?;
        let skipped = parsed
            .skipped
            .iter()
            .map(|(id, why)| format!("{id}: {why}"))
            .collect();
        Self::from_geo(name, parsed.geo, skipped, home_lat_lon)
    }

    fn from_geo(
        name: &str,
        geo: GeoFootprints,
        skipped: Vec<String>,
        home_lat_lon: Option<[f64; 2]>,
    ) -> Result<Self, PlanFailure> {
        let home = home_lat_lon.map(|[lat_deg, lon_deg]| GeodeticHome { lat_deg, lon_deg });
        let local = geo.project(home).map_err(|e| parse_failure(name, e))?;
        let frame = frame_at(
            local.home.lat_deg,
            local.home.lon_deg,
            &format!("{name}: home"),
        )?;
        Ok(Self {
            name: name.to_string(),
            kind: MapKind::Footprints,
            source: Source::Footprints(Arc::new(Footprints {
                geo: Arc::new(geo),
                local,
                skipped: Arc::new(skipped),
            })),
            frame: Some(frame),
            default_start_ne: Some([0.0, 0.0]),
            default_goal_ne: None,
            terrain: None,
        })
    }

    /// A MovingAI `.map` from its text, north up (row 0 of the file is the northern edge), 1 m
    /// cells, origin at the south-west corner.
    pub fn from_movingai(name: &str, text: &str) -> Result<Self, PlanFailure> {
        let m = skyplan_map::movingai::parse_map(text).map_err(|e| parse_failure(name, e))?;
        let grid = skyplan_imagemap::grid_from_movingai(&m).map_err(|e| parse_failure(name, e))?;
        Ok(Self::grid_world(name.to_string(), MapKind::MovingAi, grid))
    }

    /// An occupancy image (PNG or PGM bytes) read with a ROS map_server YAML's rules (or
    /// [`MapYaml::bare`] for a bare image).
    pub fn from_image(
        name: &str,
        image_bytes: &[u8],
        meta: &MapYaml,
        unknown_free: bool,
    ) -> Result<Self, PlanFailure> {
        let raster =
            skyplan_imagemap::decode_image(image_bytes).map_err(|e| parse_failure(name, e))?;
        let map = skyplan_imagemap::image_map_with(&raster, meta, unknown_free)
            .map_err(|e| parse_failure(name, e))?;
        Ok(Self::grid_world(name.to_string(), MapKind::Image, map.grid))
    }

    /// [`World::from_image`], refused before decoding when the image (one grey byte per pixel,
    /// plus alpha, plus the grid) would not fit in `limits`.
    pub fn from_image_within(
        name: &str,
        image_bytes: &[u8],
        meta: &MapYaml,
        unknown_free: bool,
        limits: &Limits,
    ) -> Result<Self, PlanFailure> {
        let (w, h) =
            skyplan_imagemap::image_size(image_bytes).map_err(|e| parse_failure(name, e))?;
        let pixels = u64::from(w) * u64::from(h);
        check_memory(
            pixels.saturating_mul(4),
            limits,
            &format!("{name}: a {w} × {h} image"),
            "use a smaller image",
        )?;
        Self::from_image(name, image_bytes, meta, unknown_free)
    }

    /// A random workspace of `width` × `height` 1 m cells, each blocked with probability
    /// `density`; its default start and goal are the farthest-apart pair of 16 free cells drawn
    /// with the same seed.
    pub fn random(width: u32, height: u32, density: f64, seed: u64) -> Result<Self, PlanFailure> {
        let grid = skyplan_imagemap::random_workspace(height, width, density, seed)
            .map_err(|e| PlanFailure::bad_request(format!("random workspace: {e}")))?;
        let cells = skyplan_imagemap::draw_free_cells(&grid, 16, seed);
        let dist2 = |a: Cell, b: Cell| {
            u64::from(a.row.abs_diff(b.row)).pow(2) + u64::from(a.col.abs_diff(b.col)).pow(2)
        };
        let mut drawn: Option<(Cell, Cell)> = None;
        for (i, &a) in cells.iter().enumerate() {
            for &b in &cells[i + 1..] {
                if drawn.is_none_or(|(x, y)| dist2(a, b) > dist2(x, y)) {
                    drawn = Some((a, b));
                }
            }
        }
        let name = format!("random {width}x{height} (density {density}, seed {seed})");
        let mut world = Self::grid_world(name, MapKind::Random, grid);
        if let (Some((a, b)), Source::Grid(g)) = (drawn, &world.source) {
            let (an, ae) = g.center_ne(a);
            let (bn, be) = g.center_ne(b);
            world.default_start_ne = Some([an, ae]);
            world.default_goal_ne = Some([bn, be]);
        }
        Ok(world)
    }

    /// [`World::random`], refused before allocating when the grid would not fit in `limits`.
    pub fn random_within(
        width: u32,
        height: u32,
        density: f64,
        seed: u64,
        limits: &Limits,
    ) -> Result<Self, PlanFailure> {
        let cells = u64::from(width) * u64::from(height);
        check_memory(
            cells.saturating_mul(2),
            limits,
            &format!("a random {width}x{height} workspace"),
            "use a smaller workspace",
        )?;
        Self::random(width, height, density, seed)
    }

    /// A grid given directly (row 0 is the southern edge; see `Grid2`).
    pub fn from_grid(name: &str, grid: Grid2) -> Self {
        Self::grid_world(name.to_string(), MapKind::Grid, grid)
    }

    /// Gives a map without a geodetic home (images, MovingAI, random, grids) one, so that
    /// waypoints get lat/lon and positions may be given as lat/lon; moves a footprint map's
    /// local frame to this home (its footprints are projected again). Colliders maps carry
    /// their own home and refuse another.
    pub fn with_home(mut self, lat_deg: f64, lon_deg: f64) -> Result<Self, PlanFailure> {
        if self.kind == MapKind::Colliders {
            return Err(PlanFailure::bad_request(
                "home: a colliders map carries its own home (line 1); drop the extra home",
            ));
        }
        let frame = frame_at(lat_deg, lon_deg, "home")?;
        if let Source::Footprints(f) = &self.source {
            let local = f
                .geo
                .project(Some(GeodeticHome { lat_deg, lon_deg }))
                .map_err(|e| parse_failure(&self.name, e))?;
            self.source = Source::Footprints(Arc::new(Footprints {
                geo: Arc::clone(&f.geo),
                local,
                skipped: Arc::clone(&f.skipped),
            }));
        }
        if let Some(t) = &self.terrain {
            self.terrain = Some(Arc::new(
                Terrain::new(t.dem().clone(), frame)
                    .map_err(|e| PlanFailure::bad_request(format!("terrain: {e}")))?,
            ));
        }
        self.frame = Some(frame);
        Ok(self)
    }

    /// Puts the map on the ground `dem` describes (named `name` in messages): its home must
    /// lie on the DEM. Plans then keep `alt_agl_m` above the ground (buildings' heights count
    /// from the ground under them), and altitudes stay above home, whose ground is the DEM's
    /// height there. Needs a map with a geodetic home (colliders, footprints, or `with_home`).
    ///
    /// ```
    /// use skyplan_map::terrain::Dem;
    /// // Flat ground 100 m above sea level around the FCND map's home.
    /// let dem = Dem::geographic(3, 3, vec![100.0; 9], [-122.41, 37.80], [0.01, 0.01])?;
    /// let world = skyplan_plan::World::fcnd_city().with_terrain("flat.tif", dem)?;
    /// assert_eq!(world.terrain().map(|t| t.home_ground_amsl_m()), Some(100.0));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_terrain(mut self, name: &str, dem: Dem) -> Result<Self, PlanFailure> {
        let frame = self.frame.ok_or_else(|| {
            PlanFailure::bad_request(format!(
                "terrain: {} has no geodetic home to place {name} about; give the map a home (--home LAT,LON)",
                self.name
            ))
        })?;
        let t = Terrain::new(dem, frame)
            .map_err(|e| PlanFailure::bad_request(format!("terrain: {name}: {e}")))?;
        self.terrain = Some(Arc::new(t));
        Ok(self)
    }

    /// The ground under the map, when it was given one.
    pub fn terrain(&self) -> Option<&Terrain> {
        self.terrain.as_deref()
    }

    /// The terrain, shared (for a simulator that keeps it while it runs).
    pub fn terrain_shared(&self) -> Option<Arc<Terrain>> {
        self.terrain.clone()
    }

    /// Replaces the default start and goal (metres north,east of the map's origin).
    pub fn with_defaults(mut self, start_ne: Option<[f64; 2]>, goal_ne: Option<[f64; 2]>) -> Self {
        self.default_start_ne = start_ne;
        self.default_goal_ne = goal_ne;
        self
    }

    /// The name used in messages and outputs.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// What the world was loaded from.
    pub fn kind(&self) -> MapKind {
        self.kind
    }

    /// The boxes of a colliders map.
    pub fn colliders(&self) -> Option<&CollidersMap> {
        match &self.source {
            Source::Colliders(m) => Some(m),
            Source::Grid(_) | Source::Footprints(_) => None,
        }
    }

    /// The footprints of a GeoJSON map, in the local frame about its home.
    pub fn footprints(&self) -> Option<&FootprintMap> {
        match &self.source {
            Source::Footprints(f) => Some(&f.local),
            Source::Grid(_) | Source::Colliders(_) => None,
        }
    }

    /// What a user should know about how the map was read, one sentence each: footprints at the
    /// default height, OpenStreetMap buildings left out (the first three named). Empty for
    /// other maps.
    pub fn notes(&self) -> Vec<String> {
        let Source::Footprints(f) = &self.source else {
            return Vec::new();
        };
        let mut notes = Vec::new();
        if f.geo.default_heights > 0 {
            notes.push(format!(
                "{} of {} buildings at the default height {} m (no height or building:levels)",
                f.geo.default_heights,
                f.geo.buildings.len(),
                f.geo.default_height_m
            ));
        }
        if let Some(first) = f.skipped.first() {
            let n = f.skipped.len();
            let shown: Vec<&str> = f.skipped.iter().take(3).map(String::as_str).collect();
            let more = if n > 3 {
                format!("; {} more", n - 3)
            } else {
                String::new()
            };
            notes.push(format!(
                "{n} building{} skipped: {}{more}",
                if n == 1 { "" } else { "s" },
                if n == 1 {
                    first.clone()
                } else {
                    shown.join("; ")
                }
            ));
        }
        notes
    }

    /// The number of obstacles of a map made of them: boxes of a colliders map, footprints
    /// (polygons) of a GeoJSON map.
    pub fn obstacle_count(&self) -> Option<usize> {
        match &self.source {
            Source::Colliders(m) => Some(m.boxes.len()),
            Source::Footprints(f) => Some(f.local.footprints.len()),
            Source::Grid(_) => None,
        }
    }

    /// The fixed grid of an image, MovingAI, random or given grid map (colliders and footprint
    /// grids depend on the altitude, margin and cell size: see `Session::grid`).
    pub fn fixed_grid(&self) -> Option<&Grid2> {
        match &self.source {
            Source::Grid(g) => Some(g),
            Source::Colliders(_) | Source::Footprints(_) => None,
        }
    }

    /// The local frame about the geodetic home, if the map has one.
    pub fn frame(&self) -> Option<&LocalFrame> {
        self.frame.as_ref()
    }

    /// The default start and goal, metres north,east (the home and a far corner on the bundled
    /// map; drawn free cells on random maps).
    pub fn default_endpoints_ne(&self) -> (Option<[f64; 2]>, Option<[f64; 2]>) {
        (self.default_start_ne, self.default_goal_ne)
    }

    /// The horizontal extent every planner accepts: the grid's extent at this cell size
    /// (`floor(min(north − half))` … as `Grid2::from_colliders` lays it) for colliders maps, the
    /// grid's for the others. The 3D planners' flight volume covers at least this.
    pub fn bounds_ne(&self, cell_m: f64) -> BoundsNe {
        let cell_m = if cell_m.is_finite() && cell_m > 0.0 {
            cell_m
        } else {
            1.0
        };
        let span = |lo: f64, hi: f64| ((hi - lo) / cell_m).ceil().max(1.0) * cell_m;
        match &self.source {
            Source::Grid(g) => grid_bounds(g),
            Source::Footprints(f) => {
                // As `Grid2::from_footprints` lays its grid out.
                let (lo, hi) = f.local.bbox_ne();
                let (north_min_m, east_min_m) = (lo[0].floor(), lo[1].floor());
                BoundsNe {
                    north_min_m,
                    north_max_m: north_min_m + span(north_min_m, hi[0]),
                    east_min_m,
                    east_max_m: east_min_m + span(east_min_m, hi[1]),
                }
            }
            Source::Colliders(map) => {
                let lo = |f: fn(&skyplan_map::colliders::ObstacleBox) -> f64| {
                    map.boxes
                        .iter()
                        .map(f)
                        .fold(f64::INFINITY, f64::min)
                        .floor()
                };
                let hi = |f: fn(&skyplan_map::colliders::ObstacleBox) -> f64| {
                    map.boxes.iter().map(f).fold(f64::NEG_INFINITY, f64::max)
                };
                let north_min_m = lo(|b| b.north_m - b.half_north_m);
                let east_min_m = lo(|b| b.east_m - b.half_east_m);
                let north_max = hi(|b| b.north_m + b.half_north_m);
                let east_max = hi(|b| b.east_m + b.half_east_m);
                BoundsNe {
                    north_min_m,
                    north_max_m: north_min_m + span(north_min_m, north_max),
                    east_min_m,
                    east_max_m: east_min_m + span(east_min_m, east_max),
                }
            }
        }
    }
}

/// The extent of a grid in metres.
pub(crate) fn grid_bounds(g: &Grid2) -> BoundsNe {
    let f = g.frame();
    BoundsNe {
        north_min_m: f.origin_north_m,
        north_max_m: f.origin_north_m + f64::from(g.rows()) * f.cell_m,
        east_min_m: f.origin_east_m,
        east_max_m: f.origin_east_m + f64::from(g.cols()) * f.cell_m,
    }
}

//! Building footprints from OpenStreetMap: XML (`.osm`, read with `roxmltree`) and PBF
//! (`.osm.pbf`, read with `osmpbf`), both from bytes (no I/O here).
//!
//! A building is a closed way tagged `building` (any value but `no`), or a relation of type
//! `multipolygon` tagged `building`, whose `outer` (or role-less) and `inner` member ways are
//! joined end to end into closed rings, each inner ring going to the outer ring that holds it.
//! The tags are the building's properties, read as [`crate::footprints`] reads a GeoJSON
//! feature's (`height`, else `building:levels` × 3 m, else the default; `min_height`), so an OSM
//! file and the same buildings as GeoJSON are the same map.
//!
//! Extracts cut at a boundary hold buildings whose nodes or member ways are missing, and real
//! data holds a few broken outlines: such a building is **skipped and named** (the front ends
//! report them), never dropped silently; a file that is not OSM at all is an error naming the
//! place.
//!
//! ```
//! use skyplan_map::osm::{parse_osm_xml, OsmId};
//! let text = r#"<osm version="0.6">
//!   <node id="1" lat="60.1700" lon="24.9400"/> <node id="2" lat="60.1700" lon="24.9402"/>
//!   <node id="3" lat="60.1701" lon="24.9402"/>
//!   <way id="10"><nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="1"/>
//!     <tag k="building" v="yes"/><tag k="building:levels" v="4"/></way>
//!   <way id="11"><nd ref="1"/><nd ref="2"/><tag k="building" v="yes"/></way>
//! </osm>"#;
//! let b = parse_osm_xml(text, 10.0)?;
//! assert_eq!(b.ids, vec![OsmId::Way(10)]);
//! assert_eq!(b.geo.buildings[0].height_m, 12.0);
//! assert_eq!(b.skipped[0].0, OsmId::Way(11)); // not closed
//! # Ok::<(), skyplan_map::footprints::FootprintError>(())
//! ```

use crate::footprints::{FootprintError, GeoFootprints, HeightSource, err};

/// Most building positions (way node references) an extract may hold: a city of a few hundred
/// thousand buildings. Its nodes are held in a map while the buildings are assembled, about
/// 50 bytes each.
pub const MAX_VERTICES: usize = 5_000_000;
use serde_json::{Map, Value, json};
// foldhash: ids are looked up once per node of the extract; SipHash made that a sixth of the
// read time. Seeded per process, so crafted ids cannot aim at collisions.
use foldhash::{HashMap, HashMapExt, HashSet, HashSetExt};
use std::fmt;

/// Largest XML file read, bytes (its tree takes several times this in memory).
pub const MAX_XML_BYTES: usize = 256 << 20;

/// An OpenStreetMap element a building came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum OsmId {
    /// A closed way.
    Way(i64),
    /// A multipolygon relation.
    Relation(i64),
}

impl fmt::Display for OsmId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Way(id) => write!(f, "way {id}"),
            Self::Relation(id) => write!(f, "relation {id}"),
        }
    }
}

/// The buildings of an OSM file, in longitude/latitude, with where each came from and what was
/// skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct OsmBuildings {
    /// The buildings (each `GeoBuilding::feature` is its index here).
    pub geo: GeoFootprints,
    /// The element of each building, in the same order.
    pub ids: Vec<OsmId>,
    /// Buildings that could not be made, each with the reason in a sentence.
    pub skipped: Vec<(OsmId, String)>,
}

/// One element as both readers give it.
enum Element<'a> {
    Node(i64, [f64; 2]),
    Way(i64, Vec<i64>, Vec<(&'a str, &'a str)>),
    /// Id, members (way id, role), tags; members that are not ways are left out.
    Relation(i64, Vec<(i64, &'a str)>, Vec<(&'a str, &'a str)>),
}

/// Reads the same file several times, element by element (three passes, so that only the
/// buildings' ways and nodes are kept).
trait Source {
    /// Every way and relation (and, with `with_nodes`, every node), in file order.
    fn scan(&self, with_nodes: bool, f: &mut dyn FnMut(Element<'_>)) -> Result<(), FootprintError>;

    /// The positions of the `wanted` nodes, into `out`.
    fn nodes(
        &self,
        wanted: &HashSet<i64>,
        out: &mut HashMap<i64, [f64; 2]>,
    ) -> Result<(), FootprintError> {
        self.scan(true, &mut |e| {
            if let Element::Node(id, p) = e
                && wanted.contains(&id)
            {
                out.insert(id, p);
            }
        })
    }
}

/// Buildings from OSM XML text.
///
/// Errors: text that is not XML (with line and column), a root other than `<osm>`, a node,
/// way or relation without a valid `id`, a node's `lat`/`lon` missing or out of range, more
/// than [`MAX_VERTICES`] building positions, no building at all.
pub fn parse_osm_xml(text: &str, default_height_m: f64) -> Result<OsmBuildings, FootprintError> {
    if text.len() > MAX_XML_BYTES {
        return Err(err(
            None,
            "file",
            format!(
                "{} MB of XML is more than the {} MB read; convert it to .osm.pbf",
                text.len() >> 20,
                MAX_XML_BYTES >> 20
            ),
        ));
    }
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let p = e.pos();
        err(
            None,
            "XML",
            format!("line {}, column {}: {e}", p.row, p.col),
        )
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "osm" {
        return Err(err(
            None,
            "root element",
            format!("expected <osm>, found <{}>", root.tag_name().name()),
        ));
    }
    buildings(&XmlSource(root), default_height_m)
}

struct XmlSource<'a, 'input>(roxmltree::Node<'a, 'input>);

fn attr_i64(n: roxmltree::Node<'_, '_>, name: &str, what: &str) -> Result<i64, FootprintError> {
    n.attribute(name)
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| {
            err(
                None,
                format!("line {}, {what} {name}", line_of(n)),
                format!(
                    "expected an integer, found {}",
                    n.attribute(name).map_or("nothing".to_string(), |v| format!(
                        "\"{}\"",
                        crate::footprints::shorten(v)
                    ))
                ),
            )
        })
}

fn line_of(n: roxmltree::Node<'_, '_>) -> u32 {
    n.document().text_pos_at(n.range().start).row
}

fn tags_of<'a>(n: roxmltree::Node<'a, '_>) -> Vec<(&'a str, &'a str)> {
    n.children()
        .filter(|c| c.has_tag_name("tag"))
        .filter_map(|c| Some((c.attribute("k")?, c.attribute("v")?)))
        .collect()
}

impl Source for XmlSource<'_, '_> {
    fn scan(&self, with_nodes: bool, f: &mut dyn FnMut(Element<'_>)) -> Result<(), FootprintError> {
        for n in self.0.children().filter(roxmltree::Node::is_element) {
            match n.tag_name().name() {
                "node" if with_nodes => {
                    let id = attr_i64(n, "id", "node")?;
                    let coord = |name: &str, range: f64| {
                        n.attribute(name)
                            .and_then(|v| v.parse::<f64>().ok())
                            .filter(|v| v.abs() <= range)
                            .ok_or_else(|| {
                                err(
                                    None,
                                    format!("line {}, node {id} {name}", line_of(n)),
                                    format!("expected a number of degrees within ±{range}"),
                                )
                            })
                    };
                    f(Element::Node(
                        id,
                        [coord("lon", 180.0)?, coord("lat", 90.0)?],
                    ));
                }
                "way" => {
                    let id = attr_i64(n, "id", "way")?;
                    let refs = n
                        .children()
                        .filter(|c| c.has_tag_name("nd"))
                        .map(|c| attr_i64(c, "ref", &format!("way {id} nd")))
                        .collect::<Result<_, _>>()?;
                    f(Element::Way(id, refs, tags_of(n)));
                }
                "relation" => {
                    let id = attr_i64(n, "id", "relation")?;
                    let mut members = Vec::new();
                    for m in n.children().filter(|c| c.has_tag_name("member")) {
                        if m.attribute("type") == Some("way") {
                            let r = attr_i64(m, "ref", &format!("relation {id} member"))?;
                            members.push((r, m.attribute("role").unwrap_or("")));
                        }
                    }
                    f(Element::Relation(id, members, tags_of(n)));
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Buildings from OSM PBF bytes.
///
/// Errors: bytes that are not a PBF file (the decoder's reason), more than [`MAX_VERTICES`]
/// building positions, no building at all.
pub fn parse_osm_pbf(bytes: &[u8], default_height_m: f64) -> Result<OsmBuildings, FootprintError> {
    buildings(&PbfSource(bytes), default_height_m)
}

struct PbfSource<'a>(&'a [u8]);

fn pbf_error(e: osmpbf::Error) -> FootprintError {
    err(None, "PBF", format!("not a readable .osm.pbf file: {e}"))
}

fn degrees(lat: i32, lon: i32) -> [f64; 2] {
    [f64::from(lon) / 1e7, f64::from(lat) / 1e7]
}

impl Source for PbfSource<'_> {
    fn scan(&self, with_nodes: bool, f: &mut dyn FnMut(Element<'_>)) -> Result<(), FootprintError> {
        for blob in osmpbf::BlobReader::new(self.0) {
            let blob = blob.map_err(pbf_error)?;
            let osmpbf::BlobDecode::OsmData(block) = blob.decode().map_err(pbf_error)? else {
                continue;
            };
            for group in block.groups() {
                if with_nodes {
                    for n in group.nodes() {
                        f(Element::Node(
                            n.id(),
                            degrees(n.decimicro_lat(), n.decimicro_lon()),
                        ));
                    }
                    for n in group.dense_nodes() {
                        f(Element::Node(
                            n.id(),
                            degrees(n.decimicro_lat(), n.decimicro_lon()),
                        ));
                    }
                }
                for w in group.ways() {
                    f(Element::Way(w.id(), w.refs().collect(), pbf_tags(w.tags())));
                }
                for r in group.relations() {
                    let members = r
                        .members()
                        .filter(|m| m.member_type == osmpbf::RelMemberType::Way)
                        .map(|m| (m.member_id, m.role().unwrap_or("")))
                        .collect();
                    f(Element::Relation(r.id(), members, pbf_tags(r.tags())));
                }
            }
        }
        Ok(())
    }

    /// The blocks are inflated and decoded in parallel (rayon, as osmpbf's own parallel reader
    /// does): on a city extract this pass, over every node, is the longest.
    fn nodes(
        &self,
        wanted: &HashSet<i64>,
        out: &mut HashMap<i64, [f64; 2]>,
    ) -> Result<(), FootprintError> {
        use rayon::iter::{ParallelBridge, ParallelIterator};
        let per_block: Vec<Vec<(i64, [f64; 2])>> = osmpbf::BlobReader::new(self.0)
            .par_bridge()
            .map(|blob| {
                let mut out = Vec::new();
                if let osmpbf::BlobDecode::OsmData(block) = blob?.decode()? {
                    for group in block.groups() {
                        let mut keep = |id: i64, p: [f64; 2]| {
                            if wanted.contains(&id) {
                                out.push((id, p));
                            }
                        };
                        for n in group.nodes() {
                            keep(n.id(), degrees(n.decimicro_lat(), n.decimicro_lon()));
                        }
                        for n in group.dense_nodes() {
                            keep(n.id(), degrees(n.decimicro_lat(), n.decimicro_lon()));
                        }
                    }
                }
                Ok(out)
            })
            .collect::<Result<_, osmpbf::Error>>()
            .map_err(pbf_error)?;
        for block in per_block {
            out.extend(block);
        }
        Ok(())
    }
}

fn pbf_tags<'a>(t: osmpbf::TagIter<'a>) -> Vec<(&'a str, &'a str)> {
    t.collect()
}

fn is_building(tags: &[(&str, &str)]) -> bool {
    tags.iter().any(|&(k, v)| k == "building" && v != "no")
}

/// A multipolygon relation's members as kept between passes.
struct Relation {
    id: i64,
    members: Vec<(i64, bool)>, // way id, inner
    tags: Map<String, Value>,
}

fn properties(tags: &[(&str, &str)]) -> Map<String, Value> {
    tags.iter()
        .map(|&(k, v)| (k.to_string(), Value::String(v.to_string())))
        .collect()
}

fn buildings(src: &dyn Source, default_height_m: f64) -> Result<OsmBuildings, FootprintError> {
    // Pass 1: the building relations and the ways they need.
    let mut relations = Vec::new();
    let mut wanted_ways = HashSet::new();
    src.scan(false, &mut |e| {
        if let Element::Relation(id, members, tags) = e
            && is_building(&tags)
            && tags.contains(&("type", "multipolygon"))
        {
            wanted_ways.extend(members.iter().map(|m| m.0));
            relations.push(Relation {
                id,
                members: members
                    .iter()
                    .map(|&(w, role)| (w, role == "inner"))
                    .collect(),
                tags: properties(&tags),
            });
        }
    })?;
    // Pass 2: building ways, and the relations' ways; the nodes they need.
    let mut ways: Vec<(i64, Vec<i64>, Map<String, Value>)> = Vec::new();
    let mut member_ways: HashMap<i64, Vec<i64>> = HashMap::new();
    let mut wanted_nodes = HashSet::new();
    let mut refs_kept = 0usize;
    src.scan(false, &mut |e| {
        if let Element::Way(id, refs, tags) = e {
            let building = is_building(&tags);
            let member = wanted_ways.contains(&id);
            if building || member {
                refs_kept += refs.len();
                wanted_nodes.extend(refs.iter().copied());
            }
            if member {
                member_ways.insert(id, refs.clone());
            }
            if building {
                ways.push((id, refs, properties(&tags)));
            }
        }
    })?;
    if refs_kept > MAX_VERTICES {
        return Err(err(
            None,
            "ways",
            format!(
                "the buildings have more than {MAX_VERTICES} positions; cut the extract smaller"
            ),
        ));
    }
    // Pass 3: the nodes.
    let mut nodes: HashMap<i64, [f64; 2]> = HashMap::with_capacity(wanted_nodes.len());
    src.nodes(&wanted_nodes, &mut nodes)?;
    let mut out = OsmBuildings {
        geo: GeoFootprints {
            buildings: Vec::new(),
            default_heights: 0,
            default_height_m,
            vertices: 0,
        },
        ids: Vec::new(),
        skipped: Vec::new(),
    };
    let mut add = |id: OsmId,
                   polygons: Result<Vec<Vec<Vec<i64>>>, String>,
                   tags: Map<String, Value>| {
        let polygons = match polygons.and_then(|p| located(&p, &nodes)) {
            Ok(p) => p,
            Err(why) => return out.skipped.push((id, why)),
        };
        let feature = json!({
            "type": "Feature",
            "properties": tags,
            "geometry": {"type": "MultiPolygon", "coordinates": polygons},
        });
        let index = out.geo.buildings.len();
        // The extract's positions are bounded above (MAX_VERTICES); a building on its own
        // against the footprint reader's bound.
        let mut vertices = 0;
        match crate::footprints::parse_feature(index, &feature, default_height_m, &mut vertices) {
            Ok(b) => {
                out.geo.vertices += vertices;
                out.geo.default_heights += usize::from(b.height_source == HeightSource::Default);
                out.geo.buildings.push(b);
                out.ids.push(id);
            }
            Err(e) => out.skipped.push((
                id,
                format!(
                    "{}: {}",
                    e.field
                        .replace("geometry.coordinates", "polygon")
                        .replace("properties.", "tag "),
                    e.message
                ),
            )),
        }
    };
    for (id, refs, tags) in ways {
        let closed = refs.len() >= 4 && refs.first() == refs.last();
        let polygon = if closed {
            Ok(vec![vec![refs]])
        } else {
            Err("the way is not closed (its last node is not its first)".to_string())
        };
        add(OsmId::Way(id), polygon, tags);
    }
    for r in relations {
        let polygons = assemble(&r, &member_ways, &nodes);
        add(OsmId::Relation(r.id), polygons, r.tags);
    }
    if out.geo.buildings.is_empty() {
        return Err(err(
            None,
            "buildings",
            match out.skipped.first() {
                Some((id, why)) => format!(
                    "no building could be made ({} skipped; the first, {id}: {why})",
                    out.skipped.len()
                ),
                None => {
                    "the file has no building (no way or multipolygon relation tagged building)"
                        .into()
                }
            },
        ));
    }
    Ok(out)
}

/// Polygons of node ids (rings closed: first id repeated at the end) as `[lon, lat]` positions.
fn located(
    polygons: &[Vec<Vec<i64>>],
    nodes: &HashMap<i64, [f64; 2]>,
) -> Result<Vec<Vec<Vec<[f64; 2]>>>, String> {
    polygons
        .iter()
        .map(|rings| {
            rings
                .iter()
                .map(|ring| {
                    ring.iter()
                        .map(|id| {
                            nodes
                                .get(id)
                                .copied()
                                .ok_or_else(|| format!("node {id} is not in the file"))
                        })
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// A relation's rings joined from its member ways, inner rings under the outer ring that holds
/// them: polygons of node ids.
fn assemble(
    r: &Relation,
    member_ways: &HashMap<i64, Vec<i64>>,
    nodes: &HashMap<i64, [f64; 2]>,
) -> Result<Vec<Vec<Vec<i64>>>, String> {
    let mut outer = Vec::new();
    let mut inner = Vec::new();
    for &(w, is_inner) in &r.members {
        let refs = member_ways
            .get(&w)
            .ok_or_else(|| format!("its member way {w} is not in the file"))?;
        if refs.len() < 2 {
            return Err(format!("its member way {w} has fewer than 2 nodes"));
        }
        if is_inner {
            inner.push(refs.clone());
        } else {
            outer.push(refs.clone());
        }
    }
    let outer =
        rings(outer).map_err(|end| format!("its outer ways do not close (open at node {end})"))?;
    let inner =
        rings(inner).map_err(|end| format!("its inner ways do not close (open at node {end})"))?;
    if outer.is_empty() {
        return Err("it has no outer way".into());
    }
    let at = |id: &i64| {
        nodes
            .get(id)
            .copied()
            .ok_or_else(|| format!("node {id} is not in the file"))
    };
    let outer_pts: Vec<Vec<[f64; 2]>> = outer
        .iter()
        .map(|ring| ring.iter().map(at).collect())
        .collect::<Result<_, _>>()?;
    let mut polygons: Vec<Vec<Vec<i64>>> = outer.into_iter().map(|o| vec![o]).collect();
    for hole in inner {
        let p = at(&hole[0])?;
        let k = outer_pts
            .iter()
            .position(|ring| inside(p, ring))
            .ok_or_else(|| format!("its inner ring at node {} is inside no outer ring", hole[0]))?;
        polygons[k].push(hole);
    }
    Ok(polygons)
}

/// Ways joined end to end into closed rings (each ring's first node repeated at its end), or
/// the node where one stays open.
fn rings(mut ways: Vec<Vec<i64>>) -> Result<Vec<Vec<i64>>, i64> {
    let mut out = Vec::new();
    while let Some(mut ring) = ways.pop() {
        while ring.first() != ring.last() {
            let end = ring[ring.len() - 1];
            let Some(k) = ways
                .iter()
                .position(|w| w.first() == Some(&end) || w.last() == Some(&end))
            else {
                return Err(end);
            };
            let mut next = ways.swap_remove(k);
            if next.first() != Some(&end) {
                next.reverse();
            }
            ring.extend_from_slice(&next[1..]);
        }
        out.push(ring);
    }
    Ok(out)
}

/// Whether `p` is inside the closed ring `ring` (even-odd rule, in degrees).
fn inside(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let mut odd = false;
    for w in ring.windows(2) {
        let (a, b) = (w[0], w[1]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
}

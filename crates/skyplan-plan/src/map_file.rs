//! Map files by extension ([`World::load_file`]): every front end reads `--map`/`map=` the same
//! way. The library does no I/O: the caller hands in the function that reads a file.

use crate::failure::PlanFailure;
use crate::world::{Limits, MapFormat, World};
use skyplan_imagemap::MapYaml;
use std::path::{Path, PathBuf};

/// What a map file needs besides its bytes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MapFileOptions {
    /// Metres per pixel of a bare `.png`/`.pgm` (required there, refused for every other map).
    pub resolution_m: Option<f64>,
    /// Image maps: unknown pixels (between the thresholds) count as free.
    pub unknown_free: bool,
    /// Memory limits, checked before the grid is allocated.
    pub limits: Limits,
}

/// Why a map file was not loaded. The option errors carry no words: each front end names the
/// option its own way (`--resolution`, `resolution_m=`).
#[derive(Debug)]
pub enum MapFileError<E> {
    /// The extension is none of `.csv`, `.yaml`/`.yml`, `.png`/`.pgm`, `.map`, `.geojson`,
    /// `.osm`, `.pbf`.
    UnknownType,
    /// A bare image without a resolution.
    NeedsResolution,
    /// A resolution given for a map that carries its own scale.
    ResolutionNotTaken,
    /// The reader failed on `path`: the map itself, or the image its `.yaml` names
    /// (`via_yaml`).
    Read {
        /// The file that could not be read.
        path: PathBuf,
        /// It is the image a map_server `.yaml` names.
        via_yaml: bool,
        /// The reader's error.
        error: E,
    },
    /// The file was read but is not a valid map (the failure names the file).
    Map(PlanFailure),
}

impl World {
    /// The map in `path`, by its extension: `.csv` FCND colliders, `.yaml`/`.yml` ROS
    /// map_server (its image read next to it), `.png`/`.pgm` with `options.resolution_m`, `.map`
    /// MovingAI, `.geojson` building footprints, `.osm`/`.osm.pbf` OpenStreetMap buildings (home
    /// at the data's centre; move it with [`World::with_home`]). `read` reads a file's bytes (the caller's I/O).
    ///
    /// ```
    /// use skyplan_plan::{MapFileError, MapFileOptions, World};
    /// use std::path::Path;
    /// let read = |_: &Path| Ok::<_, std::io::Error>(b"type octile\nheight 1\nwidth 3\nmap\n.@.\n".to_vec());
    /// let world = World::load_file(Path::new("tiny.map"), &MapFileOptions::default(), read).unwrap();
    /// assert_eq!(world.name(), "tiny.map");
    /// let png = World::load_file(Path::new("a.png"), &MapFileOptions::default(), read);
    /// assert!(matches!(png, Err(MapFileError::NeedsResolution)));
    /// ```
    pub fn load_file<E>(
        path: &Path,
        options: &MapFileOptions,
        mut read: impl FnMut(&Path) -> Result<Vec<u8>, E>,
    ) -> Result<World, MapFileError<E>> {
        use MapFileError::{Map, Read};
        let name = path.display().to_string();
        let format = MapFormat::of_path(path).ok_or(MapFileError::UnknownType)?;
        if options.resolution_m.is_some() && format != MapFormat::Image {
            return Err(MapFileError::ResolutionNotTaken);
        }
        let mut bytes = |p: &Path, via_yaml: bool| {
            read(p).map_err(|error| Read {
                path: p.to_path_buf(),
                via_yaml,
                error,
            })
        };
        let text = |b: Vec<u8>| {
            String::from_utf8(b).map_err(|e| {
                Map(PlanFailure::bad_request(format!(
                    "{name}: expected text, found bytes that are not UTF-8 ({e})"
                )))
            })
        };
        let image = |name: &str, b: &[u8], meta: &MapYaml| {
            World::from_image_within(name, b, meta, options.unknown_free, &options.limits)
                .map_err(Map)
        };
        match format {
            MapFormat::Colliders => {
                World::from_colliders_csv(&name, &text(bytes(path, false)?)?).map_err(Map)
            }
            MapFormat::GeoJson => {
                World::from_geojson(&name, &bytes(path, false)?, None).map_err(Map)
            }
            MapFormat::Osm | MapFormat::OsmPbf => {
                let pbf = format == MapFormat::OsmPbf;
                World::from_osm(&name, &bytes(path, false)?, None, pbf).map_err(Map)
            }
            MapFormat::MovingAi => {
                World::from_movingai(&name, &text(bytes(path, false)?)?).map_err(Map)
            }
            MapFormat::MapServer => {
                let meta = MapYaml::parse(&text(bytes(path, false)?)?)
                    .map_err(|e| Map(PlanFailure::bad_request(format!("{name}: {e}"))))?;
                let file = path.parent().unwrap_or(Path::new("")).join(&meta.image);
                image(&file.display().to_string(), &bytes(&file, true)?, &meta)
            }
            MapFormat::Image => {
                let resolution = options.resolution_m.ok_or(MapFileError::NeedsResolution)?;
                image(&name, &bytes(path, false)?, &MapYaml::bare(resolution))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn files() -> HashMap<PathBuf, Vec<u8>> {
        let pgm = b"P5\n3 2\n255\n\xff\x00\xff\xff\xff\xff".to_vec();
        let yaml = b"image: m.pgm\nresolution: 0.5\norigin: [0, 0, 0]\n".to_vec();
        HashMap::from([
            (PathBuf::from("d/m.pgm"), pgm),
            (PathBuf::from("d/m.yaml"), yaml),
            (
                PathBuf::from("d/bad.yaml"),
                b"image: gone.pgm\nresolution: 1\norigin: [0, 0, 0]\n".to_vec(),
            ),
            (PathBuf::from("d/c.csv"), city_csv()),
        ])
    }

    fn city_csv() -> Vec<u8> {
        crate::world::FCND_CITY_CSV.as_bytes().to_vec()
    }

    fn load(path: &str, resolution_m: Option<f64>) -> Result<World, MapFileError<String>> {
        let files = files();
        let options = MapFileOptions {
            resolution_m,
            ..Default::default()
        };
        World::load_file(Path::new(path), &options, |p| {
            files
                .get(p)
                .cloned()
                .ok_or(format!("no file {}", p.display()))
        })
    }

    #[test]
    fn each_format_by_extension_and_its_errors() {
        let yaml = load("d/m.yaml", None).unwrap();
        let bare = load("d/m.pgm", Some(0.5)).unwrap();
        assert_eq!(yaml.fixed_grid(), bare.fixed_grid());
        assert_eq!(
            yaml.fixed_grid().map(|g| (g.rows(), g.cols())),
            Some((2, 3))
        );
        assert!(load("d/c.csv", None).unwrap().colliders().is_some());
        assert!(matches!(
            load("d/m.pgm", None),
            Err(MapFileError::NeedsResolution)
        ));
        assert!(matches!(
            load("d/c.csv", Some(1.0)),
            Err(MapFileError::ResolutionNotTaken)
        ));
        assert!(matches!(
            load("d/m.tif", None),
            Err(MapFileError::UnknownType)
        ));
        match load("d/bad.yaml", None) {
            Err(MapFileError::Read {
                path,
                via_yaml,
                error,
            }) => {
                assert_eq!((path, via_yaml), (PathBuf::from("d/gone.pgm"), true));
                assert_eq!(error, "no file d/gone.pgm");
            }
            other => panic!(
                "expected the image's read error, got {:?}",
                other.map(|w| w.name().to_string())
            ),
        }
        match load("d/m.map", None) {
            Err(MapFileError::Read { via_yaml, .. }) => assert!(!via_yaml),
            other => panic!(
                "expected a read error, got {:?}",
                other.map(|w| w.name().to_string())
            ),
        }
    }
}

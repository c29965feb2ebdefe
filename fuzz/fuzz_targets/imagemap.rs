//! A ROS map_server YAML and a PNG/PGM image, decoded under a memory limit as `skyplan plan
//! map.yaml` does: input = u16 (little-endian) length of the YAML, the YAML, the image bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;
use skyplan_plan::{Limits, MapYaml, World};

fuzz_target!(|data: &[u8]| {
    let Some((len, rest)) = data.split_first_chunk::<2>() else {
        return;
    };
    let len = usize::from(u16::from_le_bytes(*len)).min(rest.len());
    let (yaml, image) = rest.split_at(len);
    let meta = std::str::from_utf8(yaml)
        .ok()
        .and_then(|t| MapYaml::parse(t).ok())
        .unwrap_or_else(|| MapYaml::bare(1.0));
    let limits = Limits {
        max_memory_bytes: 64 << 20,
    };
    for unknown_free in [false, true] {
        let _ = World::from_image_within("fuzz.png", image, &meta, unknown_free, &limits);
    }
});

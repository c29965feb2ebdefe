//! The FCND colliders CSV: any text is parsed or refused with a line and field, never a panic;
//! a parsed map becomes a world (its home gives the map frame).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(map) = skyplan_map::colliders::parse_colliders(text) {
        let _ = skyplan_plan::World::from_colliders("fuzz.csv", map);
    }
});

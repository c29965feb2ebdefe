//! MovingAI `.map` and `.scen` text (the first byte chooses): parsed or refused, never a panic;
//! a parsed map becomes a grid.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    if which % 2 == 0 {
        if let Ok(map) = skyplan_map::movingai::parse_map(text) {
            let _ = skyplan_imagemap::grid_from_movingai(&map);
        }
    } else {
        let _ = skyplan_map::movingai::parse_scen(text);
    }
});

//! The plan request as the TOML config (`skyplan plan --config`, even first byte) or the JSON body
//! of `POST /api/plan` (odd): parsed or refused naming the key, never a panic; a parsed request
//! is planned on a small random world under a memory limit (its time budget capped at 20 ms
//! to keep the fuzzer fast).
#![no_main]
use libfuzzer_sys::fuzz_target;
use skyplan_plan::{Limits, PlanRequest, Session, World};

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    let request: PlanRequest = if which % 2 == 0 {
        let Ok(text) = std::str::from_utf8(rest) else {
            return;
        };
        match skyplan_plan::parse_config_toml(text) {
            Ok(c) => c.request,
            Err(_) => return,
        }
    } else {
        // As skyplan-server's parse_request does.
        let de = &mut serde_json::Deserializer::from_slice(rest);
        match serde_path_to_error::deserialize(de) {
            Ok(r) => r,
            Err(_) => return,
        }
    };
    let mut request = request;
    request.time_limit_ms = Some(request.time_limit_ms.unwrap_or(20).min(20));
    let Ok(world) = World::random(24, 16, 0.2, 7) else {
        return;
    };
    let mut session = Session::new(world).with_limits(Limits {
        max_memory_bytes: 64 << 20,
    });
    let _ = session.plan(&request);
});

//! The ground station's per-message handling (`skyplan fly`): any sequence of messages from any
//! system ids — decoded from records or from a raw byte stream — is absorbed, converted and fed
//! to the flight executor without a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use skyplan_link::ground::fuzzing::GroundHarness;

fuzz_target!(|data: &[u8]| {
    let messages = skyplan_fuzz::incoming(data, &skyplan_fuzz::to_ground_ids());
    if messages.is_empty() {
        return;
    }
    let Ok(mut ground) = GroundHarness::new() else {
        return;
    };
    for m in messages {
        ground.handle(m.system_id, m.component_id, m.message, m.dt_s);
    }
});

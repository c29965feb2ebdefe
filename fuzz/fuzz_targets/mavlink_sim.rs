//! The simulator's command handling (`skyplan sim`): any sequence of messages — decoded from
//! records or from a raw byte stream — is handled without a panic, with time passing between.
#![no_main]
use libfuzzer_sys::fuzz_target;
use skyplan_link::vehicle::fuzzing::SimHarness;

fuzz_target!(|data: &[u8]| {
    let mut sim = SimHarness::new();
    for m in skyplan_fuzz::incoming(data, &skyplan_fuzz::to_vehicle_ids()) {
        let _ = sim.handle(m.message, m.dt_s);
    }
});

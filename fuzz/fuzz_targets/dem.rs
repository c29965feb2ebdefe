//! DEM files (GeoTIFF or SRTM `.hgt`, as the first byte chooses the name): read or refused,
//! never a panic; a DEM read is sampled at its centre.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    let name = if which % 2 == 0 { "N36W085.hgt" } else { "dem.tif" };
    if let Ok(dem) = skyplan_map::terrain::parse_dem(name, rest) {
        let [lat0, lat1, lon0, lon1] = dem.extent_deg();
        let _ = dem.elevation_amsl_m((lat0 + lat1) / 2.0, (lon0 + lon1) / 2.0);
    }
});

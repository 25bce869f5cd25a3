//! Siconos .dat friction problems: any text either reads or gives an error.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = signorini::io::fclib::parse_dat(std::path::Path::new("fuzz.dat"), text);
    }
});

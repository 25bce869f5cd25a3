//! Scene files: any bytes either parse and validate or give an error; never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = signorini::scene::file::Scene::from_toml(text);
    }
});

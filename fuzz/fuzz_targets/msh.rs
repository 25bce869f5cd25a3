//! .msh meshes: any bytes either read or give an error; never a panic or an allocation
//! from an unchecked count.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = signorini::io::mesh::parse_mesh(std::path::Path::new("fuzz.msh"), data);
});

// A Rust library with a render thread and thread-local state cannot be
// unmapped safely while those live, so dlclose (anariUnloadLibrary in the
// SDK loader) leaves it loaded: the same as most C++ devices in practice.
fn main() {
    println!("cargo:rustc-cdylib-link-arg=-Wl,-z,nodelete");
}

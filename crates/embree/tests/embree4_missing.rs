//! Where Embree 4 cannot be found, loading it fails with a message naming
//! every place tried and how to install it. Its own test binary, since it
//! sets the environment variables the search reads.
#![cfg(feature = "embree4")]

use raykit_embree::{Embree4, LIBRARY_ENV, PYTHON_ENV};

#[test]
fn a_missing_library_is_an_error_naming_every_place_tried() {
    let dir = std::env::temp_dir().join(format!("raykit-embree-missing-{}", std::process::id()));
    let library = dir.join("libembree4.so.4");
    let python = dir.join("python3");
    std::env::set_var(LIBRARY_ENV, &library);
    std::env::set_var(PYTHON_ENV, &python);
    let err = format!("{:#}", Embree4::load().err().expect("no Embree 4 there"));
    for tried in [
        format!("${LIBRARY_ENV} = {} (no such file)", library.display()),
        python.display().to_string(),
        "pip install embreex".to_string(),
    ] {
        assert!(err.contains(&tried), "'{tried}' not named in: {err}");
    }
}

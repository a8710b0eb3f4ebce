//! The `NAME:key=value,...` parser and the registry.

use raykit_scene::{builtin, description, SceneError, BUILTINS, BUILTIN_NAMES};

#[test]
fn names_and_descriptions_agree() {
    let names: Vec<&str> = BUILTINS.iter().map(|b| b.name).collect();
    assert_eq!(names, BUILTIN_NAMES);
    for name in BUILTIN_NAMES {
        let d = description(name).expect("every name is described");
        assert!(!d.is_empty() && !d.contains('\n'));
    }
    assert_eq!(description("teapot"), None);
}

#[test]
fn parses_names_keys_and_whitespace() {
    let s = builtin(" terrain : triangles = 2_000 , seed=9 ").unwrap();
    assert_eq!(s.name, "terrain");
    assert_eq!(s.mesh.num_triangles(), 2 * 32 * 32);
    assert_eq!(builtin("terrain:seed=9,triangles=2000").unwrap(), s);
    assert_eq!(
        builtin("cornell").unwrap(),
        builtin("cornell:seed=1").unwrap()
    );
    assert_eq!(builtin("cornell:").unwrap().name, "cornell");
    assert_eq!(
        builtin("scatter:triangles=160")
            .unwrap()
            .mesh
            .num_triangles(),
        160
    );
}

#[test]
fn unknown_scene_lists_every_name() {
    for spec in ["teapot", "", "Cornell:seed=1"] {
        let e = builtin(spec).unwrap_err();
        assert!(matches!(e, SceneError::UnknownScene { .. }), "{e:?}");
        let msg = e.to_string();
        for name in BUILTIN_NAMES {
            assert!(msg.contains(name), "{msg}");
        }
    }
}

#[test]
fn unknown_key_lists_valid_keys() {
    let msg = builtin("cornell:triangles=5").unwrap_err().to_string();
    assert!(
        msg.contains("triangles") && msg.contains("valid keys: seed"),
        "{msg}"
    );
    let msg = builtin("terrain:size=5").unwrap_err().to_string();
    assert!(msg.contains("seed, triangles"), "{msg}");
}

#[test]
fn bad_parameters_are_errors() {
    assert!(matches!(
        builtin("terrain:triangles"),
        Err(SceneError::Malformed { .. })
    ));
    assert!(matches!(
        builtin("terrain:seed=1,seed=2"),
        Err(SceneError::DuplicateKey { .. })
    ));
    for v in ["-3", "1e6", "abc", "", "99999999999999999999999"] {
        let e = builtin(&format!("terrain:triangles={v}")).unwrap_err();
        assert!(matches!(e, SceneError::BadValue { .. }), "{v}: {e:?}");
    }
    let e = builtin("scatter:triangles=10").unwrap_err();
    assert!(matches!(e, SceneError::OutOfRange { min: 80, .. }), "{e:?}");
    assert!(e.to_string().contains("out of range"));
    assert!(matches!(
        builtin("terrain:triangles=1000000000"),
        Err(SceneError::OutOfRange { .. })
    ));
}

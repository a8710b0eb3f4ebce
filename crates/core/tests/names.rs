//! Names of the run-time choices: every choice's name reads back as that
//! choice, and a wrong name's error lists every accepted name.

use raykit_core::accel::{AccelKind, BuildQuality, KdSplit};
use raykit_core::names::UnknownName;
use raykit_core::raysets::RayKind;
use raykit_core::tri::TestKind;
use std::fmt::Display;
use std::str::FromStr;

fn round_trips<T>(all: &[T])
where
    T: Copy + PartialEq + std::fmt::Debug + Display + FromStr<Err = UnknownName>,
{
    for &k in all {
        assert_eq!(k.to_string().parse::<T>(), Ok(k), "{k:?}");
    }
    let err = "no-such-name".parse::<T>().unwrap_err();
    assert_eq!(err.given, "no-such-name");
    let names: Vec<String> = all.iter().map(|k| k.to_string()).collect();
    assert_eq!(err.choices, names);
    for n in &names {
        assert!(err.to_string().contains(n.as_str()), "{err} lacks {n}");
    }
}

#[test]
fn every_choice_reads_back_from_its_name() {
    round_trips(&AccelKind::ALL);
    round_trips(&TestKind::ALL);
    round_trips(&RayKind::ALL);
    round_trips(&BuildQuality::ALL);
}

#[test]
fn from_name_agrees_with_parse() {
    for k in AccelKind::ALL {
        assert_eq!(AccelKind::from_name(k.name()), k.name().parse().ok());
    }
    assert_eq!(AccelKind::from_name("bvh16"), None);
    assert!("bvh16".parse::<AccelKind>().is_err());
}

#[test]
fn build_quality_reads_any_case_and_the_lbvh_alias() {
    assert_eq!("HIGH".parse(), Ok(BuildQuality::High));
    assert_eq!("lbvh".parse(), Ok(BuildQuality::Fast));
}

#[test]
fn kd_split_reads_game_weights_in_range_only() {
    for h in 0..=20u8 {
        let split = KdSplit::Game(h);
        assert_eq!(split.to_string().parse(), Ok(split));
    }
    assert_eq!("sah".parse(), Ok(KdSplit::Sah));
    assert_eq!("median".parse(), Ok(KdSplit::Median));
    for bad in ["game:21", "game:", "game:x", "Sah", ""] {
        let err = bad.parse::<KdSplit>().unwrap_err();
        assert_eq!(err.given, bad);
    }
}

//! The lists the test kit loops over are the library's, and each kind's `name()` is the
//! name a scene file uses for it, so a loop over `LAWS` or `BONDS` builds each kind's scene.

use stickslip::runner::record;
use stickslip::scene::{BondKind, EngineKind, ForceLawKind};
use stickslip_testkit::{BONDS, LAWS, bond_named, fig1_with, law_bond_pairs, law_named};

#[test]
fn names_are_the_scene_file_names() {
    for &law in LAWS {
        let s = fig1_with(&[&format!("junctions.force_law={}", law.name())]);
        assert_eq!(s.junctions.force_law, law, "{}", law.name());
        assert_eq!(law_named(law.name()), Some(law));
    }
    for &bond in BONDS {
        let s = fig1_with(&[&format!("junctions.bond={}", bond.name())]);
        assert_eq!(s.junctions.bond, bond, "{}", bond.name());
        assert_eq!(bond_named(bond.name()), Some(bond));
    }
    assert_eq!((law_named("hookean"), bond_named("sticky")), (None, None));
}

#[test]
fn the_lists_are_the_librarys_without_repeats() {
    assert_eq!(LAWS, &ForceLawKind::ALL[..]);
    assert_eq!(BONDS, &BondKind::ALL[..]);
    let pairs: Vec<_> = law_bond_pairs().collect();
    assert_eq!(pairs.len(), LAWS.len() * BONDS.len());
    for (i, p) in pairs.iter().enumerate() {
        assert!(!pairs[..i].contains(p), "{p:?} twice");
    }
    // `ForceLawKind::ALL` is generated from the law table itself (physics::force), so it
    // lists every law. Bond kinds: the match has no wildcard, so a new variant stops this
    // test compiling until it is named here, and then it must be in `ALL` to pass.
    for bond in [BondKind::Strong, BondKind::Weak] {
        assert!(BONDS.contains(&bond), "{bond:?}");
        match bond {
            BondKind::Strong | BondKind::Weak => {}
        }
    }
}

/// Every law and bond kind runs on both engines (a short Fig. 1 run reaches its end with
/// junction events), so a kind added to the lists is run by the kit's loops.
#[test]
fn every_kind_runs_on_every_engine() {
    for (law, bond) in law_bond_pairs() {
        for engine in [EngineKind::Fixed, EngineKind::Exact] {
            let e = if engine == EngineKind::Fixed { "fixed" } else { "exact" };
            let s = fig1_with(&[
                &format!("run.engine={e}"),
                &format!("junctions.force_law={}", law.name()),
                &format!("junctions.bond={}", bond.name()),
                "junctions.n=50",
                "run.t_end=40",
                "output.events=true",
            ]);
            let r = record(&s);
            assert!(r.completed(), "{law:?} {bond:?} {e}: {:?}", r.error);
            assert!(!r.events.is_empty(), "{law:?} {bond:?} {e}: no events");
            assert_eq!(r.samples.last().map(|x| x.t), Some(40.0), "{law:?} {bond:?} {e}");
        }
    }
}

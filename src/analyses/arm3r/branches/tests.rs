//! Unit tests of the singular branches of arms with parallel axes 2 and 3.

use super::*;
use crate::analyses::arm3r::{prepare, LoadOptions};

/// The branches of a bundled arm (nominal lengths).
fn branches_of(xml: &str) -> SingularBranches {
    let p = prepare(&crate::model::urdf::parse(xml).expect("parses"), &LoadOptions::default()).expect("a 3R arm");
    let chain = Chain3R::from_mechanism(&p.mechanism, 0.0).expect("3R");
    of(&p.mechanism, &chain).expect("axes 2 and 3 parallel")
}

#[test]
fn distinct_crossings_list_each_crossing_once_with_its_two_branches() {
    // PUMA and UR5: the fold of g meets both theta3 lines; KUKA: only the outstretched one.
    for (xml, lines) in [(include_str!("../../../../urdf/puma560.urdf"), &[0, 0, 1, 1][..]), (include_str!("../../../../urdf/ur5.urdf"), &[0, 0, 1, 1]), (include_str!("../../../../urdf/kuka_kr16.urdf"), &[0, 0])] {
        let b = branches_of(xml);
        let d = b.distinct_crossings();
        assert_eq!(Some(d.len()), b.crossings);
        for (k, (c, on)) in d.iter().enumerate() {
            // A theta3 line and the fold of g (index 2), each listing the record.
            assert_eq!(on[..], [lines[k], 2], "{}", c.name);
            assert!(on.iter().all(|&i| b.branches[i].crossings.contains(c)), "{}", c.name);
            assert!(d[..k].iter().all(|(x, _)| x != c), "{} listed twice", c.name);
        }
        // Every listed crossing is among them.
        assert!(b.branches.iter().flat_map(|x| &x.crossings).all(|c| d.iter().any(|(x, _)| *x == c)));
    }
}

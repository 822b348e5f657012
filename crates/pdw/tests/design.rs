//! The design search's report: a best design on a face of its box is named.

use pdw::design::bound_warnings;
use pdw_limit::design::DesignSpace;

#[test]
fn a_best_design_on_a_bound_is_named_with_the_side() {
    let space = DesignSpace {
        names: vec!["hip_mass".into(), "a".into()],
        lo: vec![5.0, 0.3],
        hi: vec![15.0, 0.7],
    };
    // Inside the box: nothing to say.
    assert!(bound_warnings(&space, &[10.0, 0.5]).is_empty());
    // 1 % of the range (0.1 kg, 0.004 m) from a bound is on it; 2 % is not.
    let w = bound_warnings(&space, &[5.1, 0.5]);
    assert_eq!(w.len(), 1);
    assert!(
        w[0].contains("hip_mass = 5.1 at the lower bound 5"),
        "{}",
        w[0]
    );
    assert!(bound_warnings(&space, &[5.2, 0.5]).is_empty());
    let w = bound_warnings(&space, &[10.0, 0.7]);
    assert!(w[0].contains("a = 0.7 at the upper bound 0.7"), "{}", w[0]);
    assert_eq!(bound_warnings(&space, &[15.0, 0.3]).len(), 2);
}

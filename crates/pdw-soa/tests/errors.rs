//! Bad parameters and shapes give typed errors, never panics.

use pdw_soa::*;

fn rod() -> Link {
    Link::rod([0.0, -1.0], 1.0)
}

#[test]
fn builder_rejects_bad_parameters_with_typed_errors() {
    assert_eq!(
        ChainBuilder::new().build().unwrap_err(),
        SoaError::EmptyChain
    );
    let zero_mass = Link { mass: 0.0, ..rod() };
    assert!(matches!(
        ChainBuilder::new()
            .revolute(rod())
            .revolute(zero_mass)
            .build(),
        Err(SoaError::NonPositiveMass { link: 1, .. })
    ));
    let neg_mass = Link {
        mass: -2.0,
        ..rod()
    };
    assert!(matches!(
        ChainBuilder::new().revolute(neg_mass).build(),
        Err(SoaError::NonPositiveMass { link: 0, .. })
    ));
    let neg_i = Link {
        inertia: -0.1,
        ..rod()
    };
    assert!(matches!(
        ChainBuilder::new().revolute(neg_i).build(),
        Err(SoaError::NegativeInertia { link: 0, .. })
    ));
    let nan = Link {
        com: [f64::NAN, 0.0],
        ..rod()
    };
    assert!(matches!(
        ChainBuilder::new().revolute(nan).build(),
        Err(SoaError::NonFinite {
            link: Some(0),
            what: "com[0]",
            ..
        })
    ));
    assert!(matches!(
        ChainBuilder::new()
            .gravity(f64::INFINITY)
            .revolute(rod())
            .build(),
        Err(SoaError::NonFinite {
            link: None,
            what: "gravity",
            ..
        })
    ));
    let point = Link {
        to_next: [0.0, -1.0],
        com: [0.0, 0.0],
        mass: 1.0,
        inertia: 0.0,
    };
    assert!(matches!(
        ChainBuilder::new().revolute(point).build(),
        Err(SoaError::DegenerateRevoluteInertia { link: 0 })
    ));
    assert!(matches!(
        ChainBuilder::new().prismatic([0.0, 0.0], rod()).build(),
        Err(SoaError::ZeroPrismaticAxis { link: 0, .. })
    ));
    assert!(matches!(
        Chain::new(vec![JointKind::Revolute; 2], vec![rod()], 9.81, 0.0),
        Err(SoaError::DimensionMismatch { .. })
    ));
}

#[test]
fn kernels_reject_mismatched_dimensions_with_typed_errors() {
    let chain = ChainBuilder::new()
        .revolute(rod())
        .revolute(rod())
        .build()
        .unwrap();
    let other = ChainBuilder::new().revolute(rod()).build().unwrap();
    let mut ws = Workspace::new(&chain);
    let mut out = vec![0.0; 2];
    let e = aba(
        &chain, &mut ws, &[0.0; 3], &[0.0; 2], &[0.0; 2], None, &mut out,
    )
    .unwrap_err();
    assert!(
        matches!(e, SoaError::DimensionMismatch { what: "q", .. }),
        "{e}"
    );
    let e = rnea(
        &chain, &mut ws, &[0.0; 2], &[0.0; 2], &[0.0; 1], None, &mut out,
    )
    .unwrap_err();
    assert!(
        matches!(e, SoaError::DimensionMismatch { what: "qdd", .. }),
        "{e}"
    );
    let mut small = Workspace::new(&other);
    let e = aba(
        &chain, &mut small, &[0.0; 2], &[0.0; 2], &[0.0; 2], None, &mut out,
    )
    .unwrap_err();
    assert!(matches!(e, SoaError::DimensionMismatch { .. }), "{e}");
    let mut lock = vec![0.0; 2];
    let e = pseudo_joint_dynamics(
        &chain,
        &mut ws,
        &[0.0; 2],
        &[0.0; 2],
        &[0.0; 2],
        &[2],
        None,
        &mut out,
        &mut lock,
    )
    .unwrap_err();
    assert_eq!(e, SoaError::InvalidJointIndex { index: 2, n: 2 });
    let e = pseudo_joint_dynamics(
        &chain,
        &mut ws,
        &[0.0; 2],
        &[0.0; 2],
        &[0.0; 2],
        &[1, 1],
        None,
        &mut out,
        &mut lock,
    )
    .unwrap_err();
    assert_eq!(e, SoaError::InvalidJointIndex { index: 1, n: 2 });
    // a single link cannot hold its tip point fixed in the plane: singular constraint
    let e = closed_chain_dynamics(
        &other,
        &mut Workspace::new(&other),
        &[0.1],
        &[0.0],
        &[0.0],
        &mut [0.0],
    )
    .unwrap_err();
    assert!(matches!(e, SoaError::SingularConstraint { .. }), "{e}");
}

//! The library's internals (tick labels, nearest grid points, stability runs, line clipping,
//! the legend's corner; RFC 3339 timestamps), run here rather than as unit tests so that the
//! library is not compiled a second time with `cfg(test)`.

mod plot {
    use pdw_store::plot::{clip_line, legend_corner, nearest, stability_runs, tick, tick_log};
    use plotters::prelude::SeriesLabelPosition;

    #[test]
    fn the_legend_goes_to_the_emptiest_corner() {
        let s = |pts: &[(f64, f64)]| vec![("a".to_string(), pts.to_vec())];
        let lin = ((0.0, 1.0), (0.0, 1.0));
        // Points in every corner but the lower left.
        let three = s(&[(0.9, 0.9), (0.1, 0.9), (0.9, 0.1), (0.5, 0.5)]);
        assert!(matches!(
            legend_corner(&three, lin, (false, false)),
            SeriesLabelPosition::LowerLeft
        ));
        // An empty chart area keeps the first choice, the upper right.
        assert!(matches!(
            legend_corner(&s(&[(0.5, 0.5)]), lin, (false, false)),
            SeriesLabelPosition::UpperRight
        ));
        // Log axes over x ∈ [1, 100], y ∈ [10⁻⁸, 1]: 10 is the middle of x, 10⁻⁵ in the lower
        // half of y; the upper left is empty there. On linear axes all four points have
        // x ≤ 30 (the left 30 %), so the first choice, the upper right, is empty.
        let logs = s(&[(3.0, 1e-5), (30.0, 1e-5), (10.0, 0.5), (30.0, 0.5)]);
        let r = ((1.0, 100.0), (1e-8, 1.0));
        assert!(matches!(
            legend_corner(&logs, r, (true, true)),
            SeriesLabelPosition::UpperLeft
        ));
        assert!(matches!(
            legend_corner(&logs, r, (false, false)),
            SeriesLabelPosition::UpperRight
        ));
    }

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick(&0.001), "0.001");
        assert_eq!(tick(&0.25), "0.25");
        assert_eq!(tick(&-0.15), "-0.15");
        assert_eq!(tick(&0.0100000001), "0.01");
        assert_eq!(tick(&9.999999999e-5), "1e-4");
        assert_eq!(tick(&1.5e-7), "1.5e-7");
        assert_eq!(tick(&0.0), "0");
        assert_eq!(tick_log(&0.005), "0.005");
        assert_eq!(tick_log(&0.007), "");
        assert_eq!(tick_log(&2e-9), "2e-9");
    }

    #[test]
    fn nearest_picks_closest_grid_point_in_either_order() {
        let g = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(nearest(&g, -5.0), 0);
        assert_eq!(nearest(&g, 1.4), 1);
        assert_eq!(nearest(&g, 1.6), 2);
        assert_eq!(nearest(&g, 9.0), 3);
        let r = [3.0, 2.0, 1.0, 0.0];
        assert_eq!(nearest(&r, 1.4), 2);
        assert_eq!(nearest(&r, 2.9), 0);
    }

    #[test]
    fn stability_runs_share_boundary_points_and_cover_branch() {
        let runs = stability_runs(&[true, true, false, false, true]);
        assert_eq!(runs, vec![(0..3, true), (2..5, false), (4..5, true)]);
    }

    #[test]
    fn clipped_slope_line_ends_on_box_edges() {
        // Line y = −0.1 x through the box [−1, 1] × [−1, 1]: enters at x = −1, leaves at x = 1.
        let s = clip_line((0.0, 0.0), (1.0, -0.1), -1.0, 1.0, -1.0, 1.0).unwrap();
        assert!((s[0].0 + 1.0).abs() < 1e-15 && (s[0].1 - 0.1).abs() < 1e-15);
        assert!((s[1].0 - 1.0).abs() < 1e-15 && (s[1].1 + 0.1).abs() < 1e-15);
        assert!(clip_line((0.0, 5.0), (1.0, 5.0), -1.0, 1.0, -1.0, 1.0).is_none());
    }
}

mod time {
    use pdw_store::rfc3339;
    use std::time::{Duration, UNIX_EPOCH};

    /// Known instants: the epoch, the 2000-02-29 leap day, and 2038-01-19T03:14:07Z = 2^31 − 1 s.
    #[test]
    fn rfc3339_matches_known_calendar_instants() {
        assert_eq!(rfc3339(UNIX_EPOCH), "1970-01-01T00:00:00Z");
        let leap = UNIX_EPOCH + Duration::from_secs(951_782_400 + 3_723);
        assert_eq!(rfc3339(leap), "2000-02-29T01:02:03Z");
        let y2038 = UNIX_EPOCH + Duration::from_secs(2_147_483_647);
        assert_eq!(rfc3339(y2038), "2038-01-19T03:14:07Z");
        let before = UNIX_EPOCH - Duration::from_secs(86_400);
        assert_eq!(rfc3339(before), "1969-12-31T00:00:00Z");
    }
}

//! Registration checked against known warps of the real MUN104 template (Pataky et al. 2011).

use pedo_io::IoError;
use pedo_register::footprint::bilinear;
use pedo_register::{
    correlation_over, mun104, register_one, register_trials, FootImages, MapKept, RegisterParams,
    Template, TemplateSource,
};

/// A trial made from the template: its sensel `x` holds the template's value at `g(x)`, `g` an
/// affine map (turn `deg`, scale `1/s`, shift) plus a smooth bend, on a grid of `rows × cols`.
fn warped(t: &FootImages, rows: usize, cols: usize, deg: f64, s: f64, bend: f64) -> FootImages {
    let (c, sn) = (deg.to_radians().cos(), deg.to_radians().sin());
    let (cx, cy) = (t.cols as f64 / 2.0, t.rows as f64 / 2.0);
    let (ox, oy) = (cols as f64 / 2.0 + 1.5, rows as f64 / 2.0 - 2.0);
    let peak = (0..rows * cols)
        .map(|i| {
            let (x, y) = ((i % cols) as f64 - ox, (i / cols) as f64 - oy);
            // Inverse of "turn by deg then scale by s": into the template's plane.
            let (u, v) = ((c * x + sn * y) / s, (-sn * x + c * y) / s);
            let u = u + bend * (v / 10.0).sin();
            bilinear(&t.peak, t.rows, t.cols, u + cx, v + cy)
        })
        .collect();
    FootImages::from_peak(rows, cols, peak).unwrap()
}

fn params() -> RegisterParams {
    RegisterParams::default()
}

#[test]
fn a_known_affine_and_bend_of_mun104_is_undone() {
    let tpl = mun104(true);
    let template = Template::of_images(tpl.clone(), 0.0, 64).unwrap();
    for (deg, s, bend) in [(12.0, 1.1, 1.0), (-20.0, 0.9, 1.5), (5.0, 1.2, 0.0)] {
        let trial = warped(&tpl, 80, 45, deg, s, bend);
        // Unregistered, on the template's grid (the trial's top-left corner).
        let before = correlation_over(
            &crop(&trial, tpl.rows, tpl.cols),
            &tpl.peak,
            std::iter::repeat(true),
        )
        .unwrap();
        let r = register_one(&trial, &template, &params()).unwrap();
        let after = r.correlation.unwrap();
        assert!(!r.fallback);
        assert!(
            after > 0.95,
            "turn {deg}, scale {s}, bend {bend}: correlation {after:.3} (before {before:.3})"
        );
        assert!(
            r.mask_xor_pct < 12.0,
            "turn {deg}: mask XOR {:.1} %",
            r.mask_xor_pct
        );
        // The match's map turns the template as the trial was turned (rows point down: the
        // same sign as the turn made above).
        assert!(
            (r.turn_deg - deg).abs() < 6.0,
            "turn {deg}: found {:.1}",
            r.turn_deg
        );
        assert!(r.residual_sensels < 1.0, "{}", r.residual_sensels);
    }
}

fn crop(t: &FootImages, rows: usize, cols: usize) -> Vec<f64> {
    (0..rows * cols)
        .map(|i| {
            let (r, c) = (i / cols, i % cols);
            if r < t.rows && c < t.cols {
                t.peak[r * t.cols + c]
            } else {
                0.0
            }
        })
        .collect()
}

#[test]
fn a_left_foot_mirrored_onto_the_right_template_is_not_flipped() {
    let right = mun104(true);
    let template = Template::of_images(right.clone(), 0.0, 64).unwrap();
    // A left foot: the right one mirrored, turned and moved a little.
    let left = warped(&right, 70, 40, 8.0, 1.05, 0.5).mirrored();
    let mut p = params();
    p.mirror_left = true;
    let r = register_one(&left, &template, &p).unwrap();
    assert!(!r.fallback);
    assert!(r.affine[0][0] * r.affine[1][1] - r.affine[0][1] * r.affine[1][0] > 0.0);
    assert!(r.turn_deg.abs() < 15.0, "{}", r.turn_deg);
    assert!(r.correlation.unwrap() > 0.95, "{:?}", r.correlation);
    // Not mirrored, the left foot is registered without a flip all the same (the map keeps
    // its orientation), and fits worse than mirrored.
    let unmirrored = register_one(&left, &template, &params()).unwrap();
    let det = unmirrored.affine[0][0] * unmirrored.affine[1][1]
        - unmirrored.affine[0][1] * unmirrored.affine[1][0];
    assert!(det > 0.0);
    assert!(unmirrored.turn_deg.abs() <= p.max_turn + 1e-9);
    assert!(unmirrored.correlation.unwrap() < r.correlation.unwrap());
}

#[test]
fn a_study_template_of_warped_trials_keeps_them_registered() {
    let tpl = mun104(true);
    let trials: Vec<FootImages> = [
        (0.0, 1.0, 0.0),
        (10.0, 1.1, 1.0),
        (-8.0, 0.95, -1.0),
        (4.0, 1.05, 0.5),
    ]
    .iter()
    .map(|&(d, s, b)| warped(&tpl, 75, 42, d, s, b))
    .collect();
    let mut p = params();
    p.template = "study".into();
    let out = register_trials(&trials, &TemplateSource::Study { rounds: 2 }, &p).unwrap();
    assert_eq!(out.trials.len(), 4);
    for r in &out.trials {
        assert!(r.correlation.unwrap() > 0.93, "{:?}", r.correlation);
        assert!(r.mask_xor_pct < 15.0, "{}", r.mask_xor_pct);
    }
}

#[test]
fn errors_are_typed() {
    let tpl = mun104(true);
    let template = Template::of_images(tpl.clone(), 0.0, 64).unwrap();
    let empty = FootImages::from_peak(10, 10, vec![0.0; 100]).unwrap();
    assert!(matches!(
        register_one(&empty, &template, &params()),
        Err(IoError::NoObject(_))
    ));
    assert!(matches!(
        Template::of_images(empty.clone(), 0.0, 64),
        Err(IoError::NoObject(_))
    ));
    // A trial in a study without footprint names it.
    let err =
        register_trials(&[tpl.clone(), empty], &TemplateSource::Trial(0), &params()).unwrap_err();
    assert!(err.to_string().contains("trial 1"), "{err}");
    // A template trial that is not there; images of the wrong size.
    assert!(matches!(
        register_trials(
            std::slice::from_ref(&tpl),
            &TemplateSource::Trial(3),
            &params()
        ),
        Err(IoError::InvalidInput(_))
    ));
    assert!(matches!(
        FootImages::from_peak(3, 3, vec![1.0; 8]),
        Err(IoError::InvalidInput(_))
    ));
    assert!(matches!(
        register_trials(&[], &TemplateSource::Trial(0), &params()),
        Err(IoError::InvalidInput(_))
    ));
    let mut p = params();
    p.max_turn = 400.0;
    assert!(matches!(
        register_one(&tpl, &template, &p),
        Err(IoError::Option(_))
    ));
}

/// The non-rigid step lowers the squared difference of a trial bent where no global map can
/// follow (the template's forefoot shifted sideways against its heel), below the rigid map's.
#[test]
fn the_warp_follows_a_local_bend_the_rigid_map_cannot() {
    let tpl = mun104(true);
    let template = Template::of_images(tpl.clone(), 0.0, 64).unwrap();
    // Rows 0..25 (toes, forefoot) moved 2 sensels sideways, fading out by row 40.
    let peak = (0..tpl.rows * tpl.cols)
        .map(|i| {
            let (x, y) = ((i % tpl.cols) as f64, (i / tpl.cols) as f64);
            let shift = 2.0 * ((40.0 - y) / 15.0).clamp(0.0, 1.0);
            bilinear(&tpl.peak, tpl.rows, tpl.cols, x - shift, y)
        })
        .collect();
    let trial = FootImages::from_peak(tpl.rows, tpl.cols, peak).unwrap();
    let mse = |r: &pedo_register::Registration| -> f64 {
        r.images
            .peak
            .iter()
            .zip(&tpl.peak)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / tpl.peak.len() as f64
    };
    let warped = register_one(&trial, &template, &params()).unwrap();
    let mut p = params();
    p.warp_spacing = 0.0;
    let rigid = register_one(&trial, &template, &p).unwrap();
    assert_eq!(warped.kept, MapKept::Warp);
    assert_eq!(rigid.kept, MapKept::Rigid);
    assert!(
        mse(&warped) < 0.5 * mse(&rigid),
        "MSE warp {:.1}, rigid {:.1}",
        mse(&warped),
        mse(&rigid)
    );
    assert!(warped.mask_xor_pct <= rigid.mask_xor_pct + 1.0);
}

/// A trial that already lies on the template is never moved off it: whatever the maps do, the
/// footprint kept overlaps the template at least as well as the trial as it lies (here exactly).
#[test]
fn no_registration_overlaps_worse_than_the_trial_as_it_lies() {
    let tpl = mun104(true);
    let template = Template::of_images(tpl.clone(), 0.0, 64).unwrap();
    for trial in [
        tpl.clone(),
        warped(&tpl, tpl.rows, tpl.cols, 3.0, 1.02, 0.3),
    ] {
        let unregistered = {
            let m = pedo_register::footprint::loaded_mask(&trial.peak, 0.0);
            let xor = m.iter().zip(&template.mask).filter(|(a, b)| a != b).count();
            100.0 * xor as f64 / template.mask.iter().filter(|&&v| v).count() as f64
        };
        for spacing in [0.0, 6.0] {
            let mut p = params();
            p.warp_spacing = spacing;
            let r = register_one(&trial, &template, &p).unwrap();
            assert!(
                r.mask_xor_pct <= unregistered + 1e-9,
                "spacing {spacing}: XOR {:.2} % against {unregistered:.2} % unregistered ({:?})",
                r.mask_xor_pct,
                r.kept
            );
            if r.kept == MapKept::Identity {
                assert_eq!(r.affine, [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            }
        }
    }
}

//! The trihedral-angle calculator (spherical trigonometry, `core-nostd`)
//! against an independent construction of the same corner from three edge
//! vectors (`reference::trihedral`): every angle, every edge and
//! row point, the table's rotation and tilt.

use core_nostd::calc::trihedral::{
    Corner, CornerAngles, Edge, Job, PlaneAngles, Point3, Quadrant, Setup, TiltRotaryTable,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reference::trihedral as vectors;

const TOL_DEG: f64 = 1e-9;
const TOL_MM: f64 = 1e-9;

/// Within `tol`, or `tol` relative for values above 1 (a nearly flat
/// corner puts its row points far out).
fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol * b.abs().max(1.0),
        "{what}: {a} against {b}"
    );
}

/// Random corners whose edges all rise from the vertex along the cone's
/// axis (the ones that can be milled), with the reference corner.
fn corners(n: usize) -> Vec<(PlaneAngles, Corner, vectors::Corner)> {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut out = Vec::new();
    while out.len() < n {
        let a: [f64; 3] = [
            rng.random_range(5.0..170.0),
            rng.random_range(5.0..170.0),
            rng.random_range(5.0..170.0),
        ];
        let Ok(plane) = PlaneAngles::new(a[0], a[1], a[2]) else {
            assert!(
                vectors::Corner::from_plane_angles(a[0], a[1], a[2]).is_none()
                    || a.iter().sum::<f64>() >= 359.999
                    || a.iter().any(|&x| 2.0 * x >= a.iter().sum::<f64>() - 1e-9),
                "refused a corner the reference builds: {a:?}"
            );
            continue;
        };
        let Some(r) = vectors::Corner::from_plane_angles(a[0], a[1], a[2]) else {
            panic!("the reference cannot build {a:?}");
        };
        match Corner::new(plane) {
            Ok(c) => {
                assert!(r.edges_rise(), "{a:?}: accepted, yet an edge descends");
                out.push((plane, c, r));
            }
            Err(_) => assert!(!r.edges_rise(), "{a:?}: refused, yet every edge rises"),
        }
    }
    out
}

#[test]
fn corner_angles_equal_the_vector_construction() {
    for (plane, c, r) in corners(2000) {
        let p = [plane.aob_deg(), plane.boc_deg(), plane.coa_deg()];
        let at = format!("{p:?}");
        close(c.phi_deg, r.phi_deg(), TOL_DEG, &format!("φ of {at}"));
        let sigma = [c.sigma_a_deg, c.sigma_b_deg, c.sigma_c_deg];
        let alpha = [c.alpha_a_deg, c.alpha_b_deg, c.alpha_c_deg];
        let linear = [c.linear_oa_deg, c.linear_ob_deg, c.linear_oc_deg];
        let central = [c.central_aob_deg, c.central_boc_deg, c.central_coa_deg];
        for i in 0..3 {
            close(
                sigma[i],
                r.sigma_deg()[i],
                TOL_DEG,
                &format!("σ{i} of {at}"),
            );
            close(
                alpha[i],
                r.alpha_deg()[i],
                TOL_DEG,
                &format!("α{i} of {at}"),
            );
            close(
                linear[i],
                r.linear_angles_deg()[i],
                TOL_DEG,
                &format!("ЛУ{i} of {at}"),
            );
            close(
                central[i],
                r.central_angles_deg()[i],
                TOL_DEG,
                &format!("central {i} of {at}"),
            );
        }
    }
}

#[test]
fn edge_and_row_points_equal_the_vector_construction() {
    for (plane, c, r) in corners(500) {
        let at = format!("{:?}", [plane.aob_deg(), plane.boc_deg(), plane.coa_deg()]);
        for (i, edge) in [Edge::Oa, Edge::Ob, Edge::Oc].into_iter().enumerate() {
            let p = c.edge_point(edge, 25.0);
            let q = r.edge_point(i, 25.0);
            close(p.x_mm, q[0], TOL_MM, &format!("X of edge {i} of {at}"));
            close(p.y_mm, q[1], TOL_MM, &format!("Y of edge {i} of {at}"));
            close(p.z_mm, q[2], TOL_MM, &format!("Z of edge {i} of {at}"));
        }
        let row = c.row(3.0);
        let q = r.row(3.0);
        for (i, p) in [row.a, row.b, row.c].into_iter().enumerate() {
            close(p.x_mm, q[i][0], TOL_MM, &format!("row x{i} of {at}"));
            close(p.y_mm, q[i][1], TOL_MM, &format!("row y{i} of {at}"));
        }
    }
}

#[test]
fn the_tables_rotation_and_tilt_bring_the_cone_axis_up() {
    for (plane, c, r) in corners(300) {
        for (kv, quadrant) in [
            (1, Quadrant::First),
            (2, Quadrant::Second),
            (3, Quadrant::Third),
            (4, Quadrant::Fourth),
        ] {
            for e in [0.0, 17.5, -40.0] {
                let job = Job {
                    row_step_mm: 0.5,
                    rows: 4,
                    length_a_mm: 10.0,
                    length_b_mm: 12.0,
                    length_c_mm: 8.0,
                    fillet_radius_mm: 0.0,
                    table: TiltRotaryTable::default(),
                    oa_to_x_deg: e,
                    quadrant,
                    vertex: Point3::default(),
                };
                let at = format!(
                    "{:?} k_v={kv} E={e}",
                    [plane.aob_deg(), plane.boc_deg(), plane.coa_deg()]
                );
                let s = Setup::new(&c, &job).unwrap_or_else(|e| panic!("{at}: {e}"));
                let t = r.table_setup(kv, e).expect("the reference's set-up");
                close(s.rotation_deg, t.p_deg, TOL_DEG, &format!("P of {at}"));
                close(
                    s.rotation_positive_deg,
                    t.p_positive_deg,
                    TOL_DEG,
                    &format!("P⁺ of {at}"),
                );
                close(s.tilt_deg, t.tilt_deg, TOL_DEG, &format!("tilt of {at}"));
            }
        }
    }
}

#[test]
fn mixed_plane_and_linear_angles_give_the_corner_back() {
    for (plane, c, _) in corners(300) {
        let p = [plane.aob_deg(), plane.boc_deg(), plane.coa_deg()];
        // Two faces and the linear angle at their common edge OB.
        let sas = CornerAngles {
            aob_deg: Some(p[0]),
            boc_deg: Some(p[1]),
            coa_deg: None,
            at_oa_deg: None,
            at_ob_deg: Some(c.linear_ob_deg),
            at_oc_deg: None,
        }
        .solve()
        .unwrap();
        close(
            sas.coa_deg(),
            p[2],
            1e-8,
            &format!("COA of {p:?} from AOB, BOC, ЛУ_OB"),
        );
        let third = vectors::third_plane_angle_deg(p[0], p[1], c.linear_ob_deg)
            .expect("the reference's third angle");
        close(
            sas.coa_deg(),
            third,
            1e-8,
            &format!("COA of {p:?}, reference"),
        );
        // Three linear angles.
        let aaa =
            PlaneAngles::from_linear_angles(c.linear_oa_deg, c.linear_ob_deg, c.linear_oc_deg)
                .unwrap();
        for (got, want) in [aaa.aob_deg(), aaa.boc_deg(), aaa.coa_deg()]
            .into_iter()
            .zip(p)
        {
            close(
                got,
                want,
                1e-8,
                &format!("plane angles of {p:?} from the linear ones"),
            );
        }
    }
}

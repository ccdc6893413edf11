//! Derivatives of any value (`Dx`, `Dy`, `filterwidth(v)`, `aastep` without
//! a width): their values against analytic ones and finite differences,
//! the cases where the offset runs took other branches, the redo of the
//! first call that asks, `material(s)` and `heights3`, and that a point's
//! result does not depend on the calls before it.

use std::time::Duration;

use super::*;

fn set_of(code: &str) -> ShaderSet {
    match ShaderSet::new(vec![ShaderSource::new("d", "d.lua", code)], DEFAULT_TIMEOUT) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

/// A point with a footprint: every derivative field set, none equal.
fn point(p: [f32; 3]) -> ShadeInput {
    ShadeInput {
        p,
        pw: [p[0] + 10.0, p[1] - 2.0, p[2] + 0.5],
        pc: [p[0] * 0.5, p[1] + 1.0, -4.0 + p[2]],
        n: [0.0, 0.0, 1.0],
        uv: [0.25, 0.75],
        dpdx: [0.011, 0.002, -0.003],
        dpdy: [-0.001, 0.013, 0.004],
        dpwdx: [0.021, 0.004, -0.006],
        dpwdy: [-0.002, 0.026, 0.008],
        dpcdx: [0.017, -0.001, 0.0005],
        dpcdy: [0.0015, -0.019, 0.002],
        duvdx: [0.007, -0.0025],
        duvdy: [0.0012, 0.009],
        filterwidth: 0.013,
        ..ShadeInput::default()
    }
}

fn rgb(set: &ShaderSet, i: &ShadeInput) -> [f64; 3] {
    match set.color(0, i) {
        Ok(c) => c.map(f64::from),
        Err(e) => panic!("{e}"),
    }
}

fn close(got: f64, want: f64, what: &str) {
    assert!((got - want).abs() <= 1e-6 * want.abs().max(1e-3), "{what}: got {got}, want {want}");
}

fn d(v: f32) -> f64 {
    f64::from(v)
}

#[test]
fn linear_functions_of_the_context_have_their_analytic_derivatives() {
    let i = point([0.3, 0.6, 0.1]);
    let set = set_of(
        "function color(s)
           return Dx(3 * s.P.x + 2 * s.P.y), Dy(5 * s.Pw.z - s.Pc.y), Dx(7 * s.uv.u - s.uv.v)
         end
         function specular(s)
           return Dy(s.uv.u + 4 * s.uv.v), Dx(s.Pc.z), Dy(s.P.z)
         end",
    );
    let c = rgb(&set, &i);
    close(c[0], 3.0 * d(i.dpdx[0]) + 2.0 * d(i.dpdx[1]), "Dx(3 Px + 2 Py)");
    close(c[1], 5.0 * d(i.dpwdy[2]) - d(i.dpcdy[1]), "Dy(5 Pwz - Pcy)");
    close(c[2], 7.0 * d(i.duvdx[0]) - d(i.duvdx[1]), "Dx(7 u - v)");
    let m = set.material(0, &i).unwrap();
    let s = m.specular.expect("specular").map(f64::from);
    close(s[0], d(i.duvdy[0]) + 4.0 * d(i.duvdy[1]), "Dy(u + 4 v)");
    close(s[1], d(i.dpcdx[2]), "Dx(Pcz)");
    close(s[2], d(i.dpdy[2]), "Dy(Pz)");
}

#[test]
fn the_new_fields_read_as_written() {
    let i = point([0.3, 0.6, 0.1]);
    let set = set_of("function color(s) return s.dPwdx.y + s.dPcdy.x, s.duvdx.u, s.duvdy.v end");
    let c = rgb(&set, &i);
    close(c[0], d(i.dpwdx[1]) + d(i.dpcdy[0]), "dPwdx.y + dPcdy.x");
    close(c[1], d(i.duvdx[0]), "duvdx.u");
    close(c[2], d(i.duvdy[1]), "duvdy.v");
}

#[test]
fn a_vec3_has_a_vec3_derivative_and_filterwidth_per_component() {
    let i = point([0.3, 0.6, 0.1]);
    let set = set_of(
        "function color(s)
           local v = s.P * 2 + vec3(1, 1, 1)
           local dx, dy, w = Dx(v), Dy(v), filterwidth(v)
           return dx.x + 10 * dy.y, w.z, filterwidth(s.P.x)
         end",
    );
    let c = rgb(&set, &i);
    close(c[0], 2.0 * d(i.dpdx[0]) + 20.0 * d(i.dpdy[1]), "Dx(v).x + 10 Dy(v).y");
    close(c[1], 2.0 * d(i.dpdx[2]).hypot(d(i.dpdy[2])), "filterwidth(v).z");
    close(c[2], d(i.dpdx[0]).hypot(d(i.dpdy[0])), "filterwidth(P.x)");
}

#[test]
fn a_nonlinear_function_gets_its_forward_difference() {
    let i = point([0.3, 0.6, 0.1]);
    let set = set_of("function color(s) local f = math.sin(5 * s.P.x) * s.P.y return Dx(f), Dy(f), 0 end");
    let f = |x: f64, y: f64| (5.0 * x).sin() * y;
    let (x, y) = (d(i.p[0]), d(i.p[1]));
    let c = rgb(&set, &i);
    let fd_x = f(x + d(i.dpdx[0]), y + d(i.dpdx[1])) - f(x, y);
    let fd_y = f(x + d(i.dpdy[0]), y + d(i.dpdy[1])) - f(x, y);
    // The colour passes through f32.
    assert!((c[0] - fd_x).abs() < 1e-7 && (c[1] - fd_y).abs() < 1e-7, "{c:?} vs {fd_x}, {fd_y}");
    // And a forward difference is Taylor's expansion along the step: to
    // second order, the rest is of third order in the step (about 1e-5).
    let (hx, hy) = (d(i.dpdx[0]), d(i.dpdx[1]));
    let (fx, fy) = (5.0 * (5.0 * x).cos() * y, (5.0 * x).sin());
    let (fxx, fxy) = (-25.0 * (5.0 * x).sin() * y, 5.0 * (5.0 * x).cos());
    let taylor = fx * hx + fy * hy + 0.5 * (fxx * hx * hx + 2.0 * fxy * hx * hy);
    assert!((c[0] - taylor).abs() < 5e-5, "{} vs Taylor's {taylor}", c[0]);
}

#[test]
fn offset_runs_that_took_another_branch_give_zero() {
    // At x = 0.495 the point right (x + 0.011) is past 0.5: there the
    // branch calls no derivative (a shorter tape) or takes a number where
    // the point takes a vec3 (another kind). The point down stays.
    let i = point([0.495, 0.6, 0.1]);
    let shorter = set_of(
        "function color(s)
           local a = 0
           if s.P.x < 0.5 then a = Dx(s.P.y * 3) end
           local b = 0
           if s.P.x < 0.5 then b = Dy(s.P.y * 3) end
           return a, b, 1
         end",
    );
    let c = rgb(&shorter, &i);
    assert_eq!(c[0], 0.0, "no entry in the x tape: no derivative");
    close(c[1], 3.0 * d(i.dpdy[1]), "the y tape has its entry");
    let kinds = set_of(
        "function color(s)
           local v
           if s.P.x < 0.5 then v = s.P * 2 else v = s.P.x * 2 end
           local dx, dy = Dx(v), Dy(v)
           return dx.x, dy.x, 1
         end",
    );
    let c = rgb(&kinds, &i);
    assert_eq!(c[0], 0.0, "a number in the x tape where the point has a vec3: no derivative");
    close(c[1], 2.0 * d(i.dpdy[0]), "the y tape holds a vec3");
}

#[test]
fn a_redo_caught_with_pcall_is_still_redone() {
    let i = point([0.3, 0.6, 0.1]);
    for code in [
        "function color(s)
           local ok, d = pcall(Dx, s.P.x * 4)
           if not ok then d = -1 end
           return d, 0, 0
         end",
        "function color(s)
           local ok = pcall(Dx, s.P.x * 4)
           if not ok then error('caught it') end
           return Dx(s.P.x * 4), 0, 0
         end",
    ] {
        let set = set_of(code);
        let c = rgb(&set, &i);
        close(c[0], 4.0 * d(i.dpdx[0]), code);
    }
}

#[test]
fn material_with_derivatives_returns_the_main_runs_closure_alone() {
    let i = point([0.3, 0.6, 0.1]);
    let set = set_of(
        "function material(s)
           local w = filterwidth(s.P.x * 10)
           return diffuse{ albedo = math.min(w, 1) }
         end",
    );
    let m = set.material(0, &i).unwrap();
    let c = m.closure.expect("a closure");
    assert_eq!(c.len, 1, "the offset runs' nodes are dropped");
    let w = 10.0 * d(i.dpdx[0]).hypot(d(i.dpdy[0]));
    close(f64::from(c.nodes[0].c[0][0]), w, "the colour is the width");
    // A closure kept from an offset run is stale in the main run.
    let stale = set_of(
        "local kept
         function material(s)
           local c = diffuse{}
           local n = Dx(s.P.x)
           if kept == nil then kept = c end
           return kept
         end",
    );
    let e = stale.material(0, &i).expect_err("a stale closure");
    assert_eq!(e.kind, ShaderErrorKind::BadResult, "{e}");
}

#[test]
fn bump_heights_take_derivatives_at_each_of_three_points() {
    let pts = [point([0.3, 0.6, 0.1]), point([0.35, 0.6, 0.1]), point([0.3, 0.64, 0.1])];
    let set = set_of("function height(s) return filterwidth(s.P.x * s.P.y) end");
    let three = set.heights3(0, &pts).unwrap();
    for (k, p) in pts.iter().enumerate() {
        let one = set.height(0, p).unwrap();
        assert_eq!(three[k].to_bits(), one.to_bits(), "point {k}");
        let f = |x: f64, y: f64| x * y;
        let (x, y) = (d(p.p[0]), d(p.p[1]));
        let dx = f(x + d(p.dpdx[0]), y + d(p.dpdx[1])) - f(x, y);
        let dy = f(x + d(p.dpdy[0]), y + d(p.dpdy[1])) - f(x, y);
        close(f64::from(one), dx.hypot(dy), "filterwidth(x y)");
    }
}

#[test]
fn a_points_result_does_not_depend_on_the_calls_before_it() {
    // A stripe pattern: near its edge the filtered value differs from the
    // hard step, so a first call that kept its single run would show.
    let code = "function color(s)
                  local v = aastep(0.5, (s.P.x * 20) % 1)
                  if s.P.y > 0.5 then v = v + filterwidth(s.P.z) end
                  return v, 0, 0
                end";
    let a = point([0.026, 0.2, 0.1]);
    let b = point([0.3, 0.7, 0.1]);
    let bits = |c: [f32; 3]| c.map(f32::to_bits);
    let color = |set: &ShaderSet, i: &ShadeInput| bits(set.color(0, i).unwrap());
    let first = color(&set_of(code), &a);
    let warm = set_of(code);
    let _ = color(&warm, &b);
    let after_b = color(&warm, &a);
    let again = color(&warm, &a);
    assert_eq!(first, after_b);
    assert_eq!(first, again);
    let v = f32::from_bits(first[0]);
    assert!(v > 0.0 && v < 1.0, "the edge is filtered: {v}");
    // On other threads, each with a fresh state.
    let set = set_of(code);
    std::thread::scope(|sc| {
        for order in [[a, b], [b, a]] {
            let set = &set;
            sc.spawn(move || {
                let got: Vec<_> = order.iter().map(|i| color(set, i)).collect();
                let at_a = if order[0] == a { got[0] } else { got[1] };
                assert_eq!(at_a, first);
            });
        }
    });
}

#[test]
fn aastep_without_a_width_filters_and_a_given_width_wins() {
    let i = point([0.3, 0.6, 0.1]);
    // x - edge = 2 Px - 0.6 + 0.001: just past the edge.
    let set = set_of(
        "function color(s)
           local x = 2 * s.P.x + 0.001
           return aastep(0.6, x), aastep(0.6, x, 0), aastep(0.6, x, 0.5)
         end",
    );
    let c = rgb(&set, &i);
    let x = 2.0 * d(i.p[0]) + 0.001;
    let w = 2.0 * d(i.dpdx[0]).hypot(d(i.dpdy[0]));
    close(c[0], ((x - 0.6) / w + 0.5).clamp(0.0, 1.0), "automatic width");
    assert_eq!(c[1], 1.0, "a width of 0 is the hard step");
    close(c[2], (x - 0.6) / 0.5 + 0.5, "the given width");
}

#[test]
fn triple_mode_runs_three_times_only_where_there_is_a_footprint() {
    // The run count is visible through a counter the script keeps.
    let set = set_of(
        "local runs = 0
         function color(s) runs = runs + 1 local w = Dx(s.P.x) return runs, w, 0 end",
    );
    let i = point([0.3, 0.6, 0.1]);
    let first = rgb(&set, &i)[0];
    let second = rgb(&set, &i)[0];
    assert_eq!(second - first, 3.0, "three runs a call");
    let still = ShadeInput { p: [0.3, 0.6, 0.1], ..ShadeInput::default() };
    let c = rgb(&set, &still);
    assert_eq!(c[0] - second, 1.0, "no footprint: the main run alone");
    assert_eq!(c[1], 0.0, "and no change");
    let plain = set_of("local runs = 0 function color(s) runs = runs + 1 return runs, 0, 0 end");
    let a = rgb(&plain, &i)[0];
    assert_eq!(rgb(&plain, &i)[0] - a, 1.0, "a shader without derivatives runs once");
}

#[test]
fn misuse_is_a_clear_error_at_the_scripts_line() {
    let i = point([0.3, 0.6, 0.1]);
    let err = |code: &str| match ShaderSet::new(vec![ShaderSource::new("d", "d.lua", code)], DEFAULT_TIMEOUT)
    {
        Ok(set) => set.color(0, &i).expect_err("the call fails").message,
        Err(e) => e.message,
    };
    let m = err("local w = Dx(1)\nfunction color(s) return 0, 0, 0 end");
    assert!(m.contains("d.lua:1:") && m.contains("entry function"), "{m}");
    let m = err("function color(s)\n  return Dy('a'), 0, 0\nend");
    assert!(m.contains("d.lua:2:") && m.contains("Dy: expected a number or a vec3, got a string"), "{m}");
    let m = err("function color(s)\n\n  return filterwidth(s.P.x, 2), 0, 0\nend");
    assert!(m.contains("d.lua:3:") && m.contains("filterwidth(v) takes one value"), "{m}");
    let m = err("function color(s)\n  return aastep(0.5, s.P), 0, 0\nend");
    assert!(m.contains("d.lua:2:") && m.contains("aastep: expected numbers"), "{m}");
}

#[test]
fn the_time_limit_covers_all_three_runs() {
    let set = ShaderSet::new(
        vec![ShaderSource::new("d", "d.lua", "function color(s) local w = Dx(s.P.x) while true do end end")],
        Duration::from_millis(100),
    )
    .unwrap();
    let e = set.color(0, &point([0.3, 0.6, 0.1])).expect_err("a timeout");
    assert_eq!(e.kind, ShaderErrorKind::Timeout, "{e}");
}

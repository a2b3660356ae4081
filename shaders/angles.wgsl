// Angles of directions (twin: src/shared/angles.rs): atan2 and acos as the same short
// polynomials, within 5e-7 rad of the exact angles.

//#if READS_UVS || ENVIRONMENT
// atan(a) for a in [0, 1]: a + a^3 p(a^2).
fn atan_unit(a: f32) -> f32 {
    let t = a * a;
    var p = 0.002823639;
    p = p * t - 0.015956903;
    p = p * t + 0.04250499;
    p = p * t - 0.07489009;
    p = p * t + 0.10634793;
    p = p * t - 0.14202736;
    p = p * t + 0.19992696;
    p = p * t - 0.333331;
    return a + a * (t * p);
}

// The angle of (x, y) from +x, in [-pi, pi]; 0 at the origin. Off it, y's sign bit picks the
// side, as in the twin: (-1, -0) is at -pi.
fn polynomial_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let high = max(ax, ay);
    let a = select(0.0, min(ax, ay) / select(1.0, high, high > 0.0), high > 0.0);
    var r = atan_unit(a);
    r = select(r, 0.5 * PI - r, ay > ax);
    r = select(r, PI - r, x < 0.0);
    return select(r, -r, (bitcast<u32>(y) >> 31u) == 1u);
}

// acos(x) for x in [-1, 1] (clamped): sqrt(1 - |x|) q(|x|).
fn polynomial_acos(x: f32) -> f32 {
    let a = min(abs(x), 1.0);
    var q = -0.0012624911;
    q = q * a + 0.00667009;
    q = q * a - 0.017088126;
    q = q * a + 0.03089188;
    q = q * a - 0.050174303;
    q = q * a + 0.08897899;
    q = q * a - 0.2145988;
    q = q * a + 0.5 * PI;
    let r = sqrt(1.0 - a) * q;
    return select(r, PI - r, x < 0.0);
}
//#endif

// pdamp GPU DEM kernels (WGSL, double precision: needs SHADER_F64).
//
// The same physics as the CPU engine `pdamp-dem`, written so that every pair is evaluated by
// both partners with exactly negated arithmetic (the forces on i and j are exact opposites and
// the tangential springs exact negatives), so each particle gathers its own forces in a fixed
// order: no floating-point atomics, the same bits for any launch configuration.
//
// Per step (velocity Verlet, D Sect. 2.3): drift (half kick + drift, largest displacement since
// the last neighbour build), decide (rebuild or not: indirect dispatch arguments), the
// neighbour build (clear cells, bin, sort cells, neighbour lists) when needed, forces (gravity,
// particle–particle and particle–wall contacts, per-particle energy ledger), kick.

struct Params {
    n: u32,
    n_mat: u32,
    max_nb: u32,
    max_c: u32,
    max_wc: u32,
    n_cells: u32,
    cell_cap: u32,
    n_bodies: u32,
    // first rows of the tables in `tab_f` and `tab_u`
    off_wall_f: u32,
    off_law_f: u32,
    off_body: u32,
    off_world_u: u32,
    off_wall_u: u32,
    off_law_u: u32,
    n_worlds: u32,
    off_wstep: u32,
    skin: f64,
    pad: f64,
}

@group(0) @binding(0) var<storage, read_write> P: Params;
// (x, y, z, radius)
@group(0) @binding(1) var<storage, read_write> pos: array<vec4<f64>>;
// (vx, vy, vz, mass)
@group(0) @binding(2) var<storage, read_write> vel: array<vec4<f64>>;
// (wx, wy, wz, 1/inertia)
@group(0) @binding(3) var<storage, read_write> omg: array<vec4<f64>>;
// force and torque (xyz)
@group(0) @binding(4) var<storage, read_write> frc: array<vec4<f64>>;
@group(0) @binding(5) var<storage, read_write> trq: array<vec4<f64>>;
// f64 tables, rows of 4: per world 2 rows (grid origin xyz, cell size), (gravity xyz, 0);
// per wall (from off_wall_f) 3 rows of geometry; per material pair (from off_law_f) 4 rows
// = LAW_F parameters; from off_body the body states of this chunk's steps, per (step, body)
// (position, 0), (step velocity, load flag: 1 if its loads are summed); from off_wstep per (step,
// world) (time step, active, 0, 0), (trapezoid weights of the load's single-bin DFT at the start
// and end of the step: ½h cos Ωt₀, −½h sin Ωt₀, ½h cos Ωt₁, −½h sin Ωt₁)
@group(0) @binding(6) var<storage, read_write> tab_f: array<vec4<f64>>;
// u32 tables, rows of 4: per particle (material, world, 0, 0); per world (from off_world_u)
// (cells x, y, z, first cell), (first wall, walls, 0, 0); per wall (from off_wall_u) (kind,
// body, material, two-sided); per material pair (from off_law_u) (normal law, friction law,
// clip, 0)
@group(0) @binding(7) var<storage, read_write> tab_u: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read_write> cell_count: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> cell_items: array<u32>;
// per particle max_nb + 1 entries: count, partners
@group(0) @binding(10) var<storage, read_write> nb: array<u32>;
// contacts of the last step (read) and of this step (written); swapped every step. Per
// particle max_c + 1 ids (count, partners); the state of a contact in three rows: (spring xyz,
// impact velocity), (previous normal force xyz, previous normal energy), (previous tangential
// force xyz, previous tangential energy). Wall contacts: max_wc + 1 keys (count, wall × 8 +
// feature) and four rows per contact, the fourth (normal xyz, 0).
@group(0) @binding(11) var<storage, read_write> c_ids_in: array<u32>;
@group(0) @binding(12) var<storage, read_write> c_s0_in: array<vec4<f64>>;
@group(0) @binding(13) var<storage, read_write> c_s1_in: array<vec4<f64>>;
@group(0) @binding(14) var<storage, read_write> c_s2_in: array<vec4<f64>>;
@group(0) @binding(15) var<storage, read_write> c_ids_out: array<u32>;
@group(0) @binding(16) var<storage, read_write> c_s0_out: array<vec4<f64>>;
@group(0) @binding(17) var<storage, read_write> c_s1_out: array<vec4<f64>>;
@group(0) @binding(18) var<storage, read_write> c_s2_out: array<vec4<f64>>;
@group(0) @binding(19) var<storage, read_write> w_keys_in: array<u32>;
@group(0) @binding(20) var<storage, read_write> w_st_in: array<vec4<f64>>;
@group(0) @binding(21) var<storage, read_write> w_keys_out: array<u32>;
@group(0) @binding(22) var<storage, read_write> w_st_out: array<vec4<f64>>;
// per particle 6 rows: cumulative dissipation (normal pp, tangential pp, normal pw,
// tangential pw); (cumulative wall work, stored elastic energy, 0, 0); load of its wall
// contacts with the flagged bodies: (force on the particle, 0), (torque on the bodies about
// their positions, 0); the load's single-bin DFT sums (Σ re xyz, 0), (Σ im xyz, 0)
@group(0) @binding(23) var<storage, read_write> ledger: array<vec4<f64>>;
// 0: largest squared displacement (f32 bits), 1: step within the chunk, 2: neighbour builds,
// 3: error flags, 4: first failing particle, 5: force a rebuild
@group(0) @binding(24) var<storage, read_write> ctrl: array<atomic<u32>>;
@group(0) @binding(25) var<storage, read_write> ref_pos: array<vec4<f64>>;
// indirect dispatch arguments: cells (x, y, z), particles (x, y, z); a group of its own (a
// buffer cannot be bound for writing while it drives an indirect dispatch)
@group(1) @binding(0) var<storage, read_write> args: array<u32>;

const WG: u32 = 256u;
const LAW_F: u32 = 16u;

const ERR_CELL: u32 = 1u;
const ERR_NEIGHBORS: u32 = 2u;
const ERR_NONFINITE: u32 = 4u;
const ERR_CONTACTS: u32 = 8u;
const ERR_WALL_CONTACTS: u32 = 16u;

struct CState {
    spring: vec3<f64>,
    v0: f64,
    fnp: vec3<f64>,
    ftp: vec3<f64>,
    enp: f64,
    etp: f64,
}

struct LawOut {
    el: f64,
    dis: f64,
    ft: vec3<f64>,
    en: f64,
    et: f64,
}

fn zero_state() -> CState {
    return CState(vec3<f64>(0.0lf), 0.0lf, vec3<f64>(0.0lf), vec3<f64>(0.0lf), 0.0lf, 0.0lf);
}

fn load_c(k: u32) -> CState {
    let a = c_s0_in[k];
    let b = c_s1_in[k];
    let c = c_s2_in[k];
    return CState(a.xyz, a.w, b.xyz, c.xyz, b.w, c.w);
}

fn store_c(k: u32, s: CState) {
    c_s0_out[k] = vec4<f64>(s.spring, s.v0);
    c_s1_out[k] = vec4<f64>(s.fnp, s.enp);
    c_s2_out[k] = vec4<f64>(s.ftp, s.etp);
}

fn load_w(k: u32) -> CState {
    let a = w_st_in[4u * k];
    let b = w_st_in[4u * k + 1u];
    let c = w_st_in[4u * k + 2u];
    return CState(a.xyz, a.w, b.xyz, c.xyz, b.w, c.w);
}

fn load_w_normal(k: u32) -> vec3<f64> {
    return w_st_in[4u * k + 3u].xyz;
}

fn store_w(k: u32, s: CState, normal: vec3<f64>) {
    w_st_out[4u * k] = vec4<f64>(s.spring, s.v0);
    w_st_out[4u * k + 1u] = vec4<f64>(s.fnp, s.enp);
    w_st_out[4u * k + 2u] = vec4<f64>(s.ftp, s.etp);
    w_st_out[4u * k + 3u] = vec4<f64>(normal, 0.0lf);
}

// element k of tab_f seen as a flat f64 array
fn elem(k: u32) -> f64 {
    return tab_f[k / 4u][k % 4u];
}

// d̄(ε)/ε [D Eq. 2.79] by linear interpolation in the table of 4 096 exact solutions at
// ε = k/4096 that follows the law rows (the CPU engine's dense table; below ε = 1/4096 its first
// node is used)
fn gonthier_dense(e: f64) -> f64 {
    let base = (P.off_law_f + 4u * P.n_mat * P.n_mat) * 4u;
    let s = e * 4096.0lf;
    if (s < 1.0lf) { return elem(base); }
    let k = min(u32(floor(s)), 4095u);
    let f = s - f64(k);
    let lo = elem(base + k - 1u);
    let hi = elem(base + k);
    return lo + f * (hi - lo);
}

// ε(v₀) of a velocity-dependent restitution table (pairs at element lawf(li, 14), lawf(li, 15)
// pairs): linear interpolation, constant outside (`interpolate_clamped` of the CPU engine)
fn restitution_at(li: u32, v: f64) -> f64 {
    let start = u32(lawf(li, 14u));
    let cnt = u32(lawf(li, 15u));
    if (v <= elem(start)) { return elem(start + 1u); }
    if (v >= elem(start + 2u * (cnt - 1u))) { return elem(start + 2u * cnt - 1u); }
    var k = 1u;
    while (k < cnt - 1u && elem(start + 2u * k) <= v) { k++; }
    let x0 = elem(start + 2u * (k - 1u));
    let x1 = elem(start + 2u * k);
    let y0 = elem(start + 2u * (k - 1u) + 1u);
    let y1 = elem(start + 2u * k + 1u);
    let t = (v - x0) / (x1 - x0);
    return y0 + t * (y1 - y0);
}

// parameter k of contact law li
fn lawf(li: u32, k: u32) -> f64 {
    return tab_f[P.off_law_f + 4u * li + k / 4u][k % 4u];
}

fn world_f(w: u32, row: u32) -> vec4<f64> {
    return tab_f[2u * w + row];
}

fn world_u(w: u32, row: u32) -> vec4<u32> {
    return tab_u[P.off_world_u + 2u * w + row];
}

// per (step, world): (time step, active, 0, 0) and the DFT weights
fn wstep(step: u32, w: u32, row: u32) -> vec4<f64> {
    return tab_f[P.off_wstep + 2u * (step * P.n_worlds + w) + row];
}

fn pinfo(i: u32) -> vec4<u32> {
    return tab_u[i];
}

fn flag_error(bit: u32, i: u32) {
    atomicOr(&ctrl[3], bit);
    atomicMin(&ctrl[4], i);
}

// a − (a·n) n (`pdamp_dem::math::tangential_part`)
fn tangential(a: vec3<f64>, n: vec3<f64>) -> vec3<f64> {
    return a - n * dot(a, n);
}

fn norm2(a: vec3<f64>) -> f64 {
    return a.x * a.x + a.y * a.y + a.z * a.z;
}

// e^x in double precision (Vulkan offers no f64 transcendental functions): x = k ln 2 + r,
// |r| ≤ ln2/2, Taylor series of degree 13 (error < 1e-17), scaled by 2^k.
fn exp_f64(x: f64) -> f64 {
    if (x > 709.0lf) { return 1.7976931348623157e308lf; }
    if (x < -745.0lf) { return 0.0lf; }
    let k = floor(x * 1.4426950408889634lf + 0.5lf);
    let r = (x - k * 0.6931471803691238lf) - k * 1.9082149292705877e-10lf;
    var p = 1.0lf;
    var term = 1.0lf;
    for (var m = 1; m <= 13; m++) {
        term = term * r / f64(m);
        p = p + term;
    }
    return ldexp(p, i32(k));
}

// tanh(x) for x ≥ 0 (series below 0.1, else (1 − e^{−2x})/(1 + e^{−2x}))
fn tanh_f64(x: f64) -> f64 {
    if (x < 0.1lf) {
        let x2 = x * x;
        return x * (1.0lf - x2 * (1.0lf / 3.0lf - x2 * (2.0lf / 15.0lf - x2 * (17.0lf / 315.0lf - x2 * (62.0lf / 2835.0lf)))));
    }
    if (x > 20.0lf) { return 1.0lf; }
    let e = exp_f64(-2.0lf * x);
    return (1.0lf - e) / (1.0lf + e);
}

// One contact law (`ContactModel::evaluate` of pdamp-dem) for overlap > 0: normal law
// (0 Hertz D Eq. 2.69, 1 Gonthier D Eq. 2.78, 2 Gonthier with ε(v₀) from a table, 3 Lankarani–Nikravesh D Eq. 2.77, 4 linear
// P Eq. 2–4, 5 LIGGGHTS Hertz–Mindlin), friction law (0 none, 1 regularised sliding D Eq. 2.85,
// 2 Coulomb spring–dashpot P Eq. 5, 3 Mindlin / LIGGGHTS tangential history).
fn contact_law(li: u32, r_eff: f64, m_eff: f64, delta: f64, rate: f64, n: vec3<f64>,
               v_rel: vec3<f64>, dt: f64, s: ptr<function, CState>) -> LawOut {
    let lu = tab_u[P.off_law_u + li];
    let e_eff = lawf(li, 0u);
    let g_eff = lawf(li, 1u);
    if ((*s).v0 == 0.0lf) {
        (*s).v0 = max(rate, lawf(li, 9u));
    }
    let v0 = (*s).v0;
    var el = 0.0lf;
    var dis = 0.0lf;
    var en = 0.0lf;
    var tangent_k = 0.0lf;
    var damp = 0.0lf;
    let kind = lu.x;
    if (kind == 5u) {
        let a = sqrt(r_eff * delta);
        let sn = 2.0lf * e_eff * a;
        let kn = 4.0lf / 3.0lf * e_eff * a;
        let gamma_n = lawf(li, 4u) * sqrt(sn * m_eff);
        el = kn * delta;
        dis = gamma_n * rate;
        if (lu.z != 0u) { dis = max(dis, -el); }
        en = 0.4lf * kn * delta * delta;
        tangent_k = sn;
        damp = gamma_n;
    } else if (kind == 4u) {
        let k = lawf(li, 7u);
        let d = lawf(li, 8u) * sqrt(k * m_eff);
        el = k * delta;
        dis = d * rate;
        if (lu.z != 0u) { dis = max(dis, -el); }
        en = 0.5lf * k * delta * delta;
        tangent_k = k;
        damp = d;
    } else {
        let sd = sqrt(delta);
        let kn = 4.0lf / 3.0lf * e_eff * sqrt(r_eff);
        el = kn * delta * sd;
        var c = 0.0lf;
        if (kind == 1u) {
            c = el * lawf(li, 5u) / v0;
        } else if (kind == 2u) {
            c = el * gonthier_dense(restitution_at(li, v0)) / v0;
        } else if (kind == 3u) {
            c = el * lawf(li, 6u) / v0;
        }
        dis = max(c * rate, -el);
        en = 0.4lf * kn * delta * delta * sd;
        tangent_k = 1.5lf * kn * sd;
        damp = c;
        // stability cap of the impact-velocity-scaled dashpots (as the CPU engine)
        if (dt > 0.0lf && (kind == 1u || kind == 2u || kind == 3u)) {
            let c_max = m_eff / dt;
            if (damp > c_max) {
                damp = c_max;
                dis = max(c_max * rate, -el);
            }
        }
    }
    var ft = vec3<f64>(0.0lf);
    var et = 0.0lf;
    let fk = lu.y;
    let vt = tangential(v_rel, n);
    let fn_total = el + dis;
    if (fk == 1u) {
        let mu = lawf(li, 10u);
        let eta = lawf(li, 11u);
        let speed = sqrt(norm2(vt));
        if (speed > 0.0lf) {
            ft = vt * (-mu * max(fn_total, 0.0lf) * tanh_f64(eta * speed) / speed);
        }
    } else if (fk == 2u) {
        let mu = lawf(li, 10u);
        let kt = lawf(li, 12u) * tangent_k;
        let dtc = lawf(li, 13u) * damp;
        let old_len = sqrt(norm2((*s).spring));
        var xi = tangential((*s).spring, n);
        let proj_len = sqrt(norm2(xi));
        if (proj_len > 0.0lf) { xi = xi * (old_len / proj_len); }
        xi = xi + vt * dt;
        var f = -kt * xi - dtc * vt;
        let limit = mu * max(fn_total, 0.0lf);
        let f_len = sqrt(norm2(f));
        if (f_len > limit) {
            f = f * (limit / f_len);
            if (kt > 0.0lf) { xi = -(f + dtc * vt) / kt; } else { xi = vec3<f64>(0.0lf); }
        }
        (*s).spring = xi;
        ft = f;
        et = 0.5lf * kt * norm2(xi);
    } else if (fk == 3u) {
        let mu = lawf(li, 10u);
        let a = sqrt(r_eff * delta);
        let kt = 8.0lf * g_eff * a;
        let gamma_t = lawf(li, 4u) * sqrt(kt * m_eff);
        var xi = (*s).spring + vt * dt;
        xi = xi - n * dot(xi, n);
        let shear_len = sqrt(norm2(xi));
        let ft_shear = kt * shear_len;
        let ft_friction = mu * abs(fn_total);
        if (ft_shear > ft_friction) {
            if (shear_len != 0.0lf) {
                ft = -kt * xi * (ft_friction / ft_shear);
                xi = -ft / kt;
            }
        } else {
            ft = -kt * xi - gamma_t * vt;
        }
        (*s).spring = xi;
        et = 0.5lf * kt * norm2(xi);
    }
    return LawOut(el, dis, ft, en, et);
}

fn cell_coord(x: vec3<f64>, w: u32) -> vec3<i32> {
    let o = world_f(w, 0u);
    let d = world_u(w, 0u);
    let c = floor((x - o.xyz) / o.w);
    let hi = vec3<f64>(f64(d.x - 1u), f64(d.y - 1u), f64(d.z - 1u));
    let cc = clamp(c, vec3<f64>(0.0lf), hi);
    return vec3<i32>(i32(cc.x), i32(cc.y), i32(cc.z));
}

fn cell_index(c: vec3<i32>, w: u32) -> u32 {
    let d = world_u(w, 0u);
    return d.w + (u32(c.z) * d.y + u32(c.y)) * d.x + u32(c.x);
}

fn finite3(a: vec3<f64>) -> bool {
    // NaN fails every comparison; ±inf fails the bound
    let m = 1.0e300lf;
    return abs(a.x) < m && abs(a.y) < m && abs(a.z) < m;
}

// Half kick with the forces of the last evaluation, then drift; the largest squared
// displacement since the last neighbour build goes into ctrl[0] (f32 bits, monotone).
@compute @workgroup_size(256)
fn drift(@builtin(global_invocation_id) g: vec3<u32>) {
    let i = g.x;
    if (i >= P.n) { return; }
    let ws = wstep(atomicLoad(&ctrl[1]), pinfo(i).y, 0u);
    if (ws.y == 0.0lf) { return; }
    let dt = ws.x;
    let h = 0.5lf * dt;
    var v = vel[i];
    var w = omg[i];
    let m = v.w;
    let v3 = v.xyz + frc[i].xyz * (h / m);
    let w3 = w.xyz + trq[i].xyz * (h * w.w);
    vel[i] = vec4<f64>(v3, m);
    omg[i] = vec4<f64>(w3, w.w);
    let x = pos[i];
    let x3 = x.xyz + v3 * dt;
    pos[i] = vec4<f64>(x3, x.w);
    let d = x3 - ref_pos[i].xyz;
    let d2 = f32(norm2(d));
    if (!(d2 <= 3.0e38f)) {
        flag_error(ERR_NONFINITE, i);
        atomicMax(&ctrl[0], 0x7f800000u);
    } else {
        atomicMax(&ctrl[0], bitcast<u32>(d2));
    }
}

// One thread: counts the step and decides whether the neighbour lists are rebuilt (twice the
// largest displacement reaches the skin, D Eq. 2.11); writes the indirect dispatch sizes.
@compute @workgroup_size(1)
fn decide() {
    atomicAdd(&ctrl[1], 1u);
    let d2 = bitcast<f32>(atomicLoad(&ctrl[0]));
    let skin = f32(P.skin);
    // f32 rounding of the displacement is covered by the 1e-3 margin
    let rebuild = atomicLoad(&ctrl[5]) != 0u || 4.0f * d2 * 1.001f >= skin * skin;
    if (rebuild) {
        args[0] = (P.n_cells + WG - 1u) / WG;
        args[3] = (P.n + WG - 1u) / WG;
        atomicStore(&ctrl[0], 0u);
        atomicStore(&ctrl[5], 0u);
        atomicAdd(&ctrl[2], 1u);
    } else {
        args[0] = 0u;
        args[3] = 0u;
    }
    args[1] = 1u; args[2] = 1u; args[4] = 1u; args[5] = 1u;
}

@compute @workgroup_size(256)
fn clear_cells(@builtin(global_invocation_id) g: vec3<u32>) {
    if (g.x >= P.n_cells) { return; }
    atomicStore(&cell_count[g.x], 0u);
}

@compute @workgroup_size(256)
fn bin(@builtin(global_invocation_id) g: vec3<u32>) {
    let i = g.x;
    if (i >= P.n) { return; }
    let x = pos[i];
    ref_pos[i] = x;
    let w = pinfo(i).y;
    let c = cell_index(cell_coord(x.xyz, w), w);
    let slot = atomicAdd(&cell_count[c], 1u);
    if (slot < P.cell_cap) {
        cell_items[c * P.cell_cap + slot] = i;
    } else {
        flag_error(ERR_CELL, i);
    }
}

// Sorts every cell's particles by index: the binning order (atomics) does not reach the lists.
@compute @workgroup_size(256)
fn sort_cells(@builtin(global_invocation_id) g: vec3<u32>) {
    let c = g.x;
    if (c >= P.n_cells) { return; }
    let cnt = min(atomicLoad(&cell_count[c]), P.cell_cap);
    let b = c * P.cell_cap;
    for (var k = 1u; k < cnt; k++) {
        let v = cell_items[b + k];
        var m = k;
        while (m > 0u && cell_items[b + m - 1u] > v) {
            cell_items[b + m] = cell_items[b + m - 1u];
            m--;
        }
        cell_items[b + m] = v;
    }
}

// Full neighbour list of every particle: all partners closer than r_i + r_j + skin, cells in a
// fixed order, each cell ascending.
@compute @workgroup_size(256)
fn neighbors(@builtin(global_invocation_id) g: vec3<u32>) {
    let i = g.x;
    if (i >= P.n) { return; }
    let x = pos[i];
    let w = pinfo(i).y;
    let c = cell_coord(x.xyz, w);
    let dims = vec3<i32>(world_u(w, 0u).xyz);
    var cnt = 0u;
    let base = i * (P.max_nb + 1u) + 1u;
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = c + vec3<i32>(dx, dy, dz);
                if (any(q < vec3<i32>(0)) || any(q >= dims)) { continue; }
                let ci = cell_index(q, w);
                let m = min(atomicLoad(&cell_count[ci]), P.cell_cap);
                for (var k = 0u; k < m; k++) {
                    let j = cell_items[ci * P.cell_cap + k];
                    if (j == i) { continue; }
                    let y = pos[j];
                    let cut = x.w + y.w + P.skin;
                    if (norm2(x.xyz - y.xyz) < cut * cut) {
                        if (cnt < P.max_nb) {
                            nb[base + cnt] = j;
                            cnt++;
                        } else {
                            flag_error(ERR_NEIGHBORS, i);
                        }
                    }
                }
            }
        }
    }
    nb[base - 1u] = cnt;
}

// A particle of a world that does not step this time: its contacts are carried over unchanged
// to the lists of the next step.
fn keep_contacts(i: u32) {
    let ib = i * (P.max_c + 1u);
    let cnt = c_ids_in[ib];
    c_ids_out[ib] = cnt;
    for (var o = 0u; o < cnt; o++) {
        let k = i * P.max_c + o;
        c_ids_out[ib + 1u + o] = c_ids_in[ib + 1u + o];
        c_s0_out[k] = c_s0_in[k];
        c_s1_out[k] = c_s1_in[k];
        c_s2_out[k] = c_s2_in[k];
    }
    let kb = i * (P.max_wc + 1u);
    let wc = w_keys_in[kb];
    w_keys_out[kb] = wc;
    for (var o = 0u; o < wc; o++) {
        let k = i * P.max_wc + o;
        w_keys_out[kb + 1u + o] = w_keys_in[kb + 1u + o];
        for (var r = 0u; r < 4u; r++) {
            w_st_out[4u * k + r] = w_st_in[4u * k + r];
        }
    }
}

// Forces and torques of every particle: gravity, contacts with the particles of its list and
// with the walls of its world; contact states are read from the `_in` and written to the `_out`
// lists. Energies: each pair is booked by its lower-index partner.
@compute @workgroup_size(256)
fn forces(@builtin(global_invocation_id) g: vec3<u32>) {
    let i = g.x;
    if (i >= P.n) { return; }
    let step = atomicLoad(&ctrl[1]) - 1u;
    let info = pinfo(i);
    let world = info.y;
    let ws = wstep(step, world, 0u);
    if (ws.y == 0.0lf) {
        keep_contacts(i);
        return;
    }
    let dt = ws.x;
    let xi = pos[i];
    let vi = vel[i];
    let wi4 = omg[i];
    let wi = wi4.xyz;
    let mi = vi.w;
    let grav = world_f(world, 1u).xyz;
    var f = grav * mi;
    var t = vec3<f64>(0.0lf);
    var dn_pp = 0.0lf;
    var dt_pp = 0.0lf;
    var elastic = 0.0lf;

    // Particle–particle contacts.
    let ib = i * (P.max_c + 1u);
    let old_cnt = c_ids_in[ib];
    let cb = i * P.max_c;
    var visited = 0u;
    var m = 0u;
    let nbase = i * (P.max_nb + 1u);
    let nbc = nb[nbase];
    for (var q = 0u; q < nbc; q++) {
        let j = nb[nbase + 1u + q];
        let xj = pos[j];
        let d = xi.xyz - xj.xyz;
        let dist = sqrt(norm2(d));
        let overlap = xi.w + xj.w - dist;
        let touching = dist > 0.0lf && overlap > 0.0lf;
        var k = 0xffffffffu;
        for (var o = 0u; o < old_cnt; o++) {
            if (c_ids_in[ib + 1u + o] == j) { k = o; break; }
        }
        if (!touching && k == 0xffffffffu) { continue; }
        if (k != 0xffffffffu) { visited = visited | (1u << k); }
        var n = vec3<f64>(0.0lf, 0.0lf, 1.0lf);
        if (dist > 0.0lf) { n = d / dist; }
        let vj = vel[j];
        let wj = omg[j].xyz;
        let ov = max(overlap, 0.0lf);
        let rb_i = xi.w - 0.5lf * ov;
        let rb_j = xj.w - 0.5lf * ov;
        let dv = vi.xyz - vj.xyz;
        // (dv + (a − b)): negated exactly when i and j swap
        let v_rel = dv + (cross(wi, -rb_i * n) - cross(wj, rb_j * n));
        var s = zero_state();
        if (k != 0xffffffffu) { s = load_c(cb + k); }
        var fn_vec = vec3<f64>(0.0lf);
        var ft = vec3<f64>(0.0lf);
        var en = 0.0lf;
        var et = 0.0lf;
        if (touching) {
            let li = info.x * P.n_mat + pinfo(j).x;
            let r_eff = 1.0lf / (1.0lf / xi.w + 1.0lf / xj.w);
            let m_eff = mi * vj.w / (mi + vj.w);
            let rate = -dot(n, dv);
            let lo = contact_law(li, r_eff, m_eff, overlap, rate, n, tangential(v_rel, n), dt, &s);
            fn_vec = n * (lo.el + lo.dis);
            ft = lo.ft;
            en = lo.en;
            et = lo.et;
        }
        if (i < j) {
            let w_n = -0.5lf * dot(s.fnp + fn_vec, v_rel) * dt;
            let w_t = -0.5lf * dot(s.ftp + ft, v_rel) * dt;
            dn_pp += w_n - (en - s.enp);
            dt_pp += w_t - (et - s.etp);
            elastic += en + et;
        }
        if (touching) {
            f += fn_vec + ft;
            t += -rb_i * cross(n, ft);
            s.fnp = fn_vec;
            s.ftp = ft;
            s.enp = en;
            s.etp = et;
            if (m < P.max_c) {
                c_ids_out[ib + 1u + m] = j;
                store_c(cb + m, s);
                m++;
            } else {
                flag_error(ERR_CONTACTS, i);
            }
        }
    }
    // Contacts whose partner left the list: closed like an ended contact (force falls to 0).
    for (var o = 0u; o < old_cnt; o++) {
        if ((visited & (1u << o)) != 0u) { continue; }
        let j = c_ids_in[ib + 1u + o];
        if (i > j) { continue; }
        let s = load_c(cb + o);
        let xj = pos[j];
        let d = xi.xyz - xj.xyz;
        let dist = sqrt(norm2(d));
        var n = vec3<f64>(0.0lf, 0.0lf, 1.0lf);
        if (dist > 0.0lf) { n = d / dist; }
        let dv = vi.xyz - vel[j].xyz;
        let v_rel = dv + (cross(wi, -xi.w * n) - cross(omg[j].xyz, xj.w * n));
        dn_pp += -0.5lf * dot(s.fnp, v_rel) * dt + s.enp;
        dt_pp += -0.5lf * dot(s.ftp, v_rel) * dt + s.etp;
    }
    c_ids_out[ib] = m;

    // Particle–wall contacts.
    let wu = world_u(world, 1u);
    let kb = i * (P.max_wc + 1u);
    let wold = w_keys_in[kb];
    let wb = i * P.max_wc;
    var wvisited = 0u;
    var wm = 0u;
    var dn_pw = 0.0lf;
    var dt_pw = 0.0lf;
    var work = 0.0lf;
    var load_f = vec3<f64>(0.0lf);
    var load_t = vec3<f64>(0.0lf);
    let r = xi.w;
    for (var wi_ = 0u; wi_ < wu.y; wi_++) {
        let wall = wu.x + wi_;
        let u = tab_u[P.off_wall_u + wall];
        let row = step * P.n_bodies + u.y;
        let bpos = tab_f[P.off_body + 2u * row].xyz;
        let bvel = tab_f[P.off_body + 2u * row + 1u];
        let v_wall = bvel.xyz;
        let flag = bvel.w;
        let xb = xi.xyz - bpos;
        let g0 = tab_f[P.off_wall_f + 3u * wall];
        let g1 = tab_f[P.off_wall_f + 3u * wall + 1u];
        let g2 = tab_f[P.off_wall_f + 3u * wall + 2u];
        // up to three contacts per wall: (overlap, normal, feature, curvature radius)
        var cov: array<f64, 3>;
        var cnr: array<vec3<f64>, 3>;
        var ccur: array<f64, 3>;
        var cft: array<u32, 3>;
        var nc = 0u;
        if (u.x == 0u) {
            // plane: g0 = point, g1 = unit normal
            let dd = dot(g1.xyz, xb - g0.xyz);
            var dist = dd;
            var nrm = g1.xyz;
            if (u.w != 0u && dd < 0.0lf) { dist = -dd; nrm = -g1.xyz; }
            let ovl = r - dist;
            if (ovl > 0.0lf) {
                cov[0] = ovl; cnr[0] = nrm; ccur[0] = 0.0lf; cft[0] = 0u; nc = 1u;
            }
        } else if (u.x == 1u) {
            // box: g0 = centre, g1 = half extents
            let rel = xb - g0.xyz;
            let hh = g1.xyz;
            for (var ax = 0u; ax < 3u; ax++) {
                for (var side = 0u; side < 2u; side++) {
                    var sg = 1.0lf;
                    if (side == 1u) { sg = -1.0lf; }
                    let dd = hh[ax] + sg * rel[ax];
                    let ovl = r - dd;
                    if (ovl > 0.0lf && nc < 3u) {
                        var nrm = vec3<f64>(0.0lf);
                        nrm[ax] = sg;
                        cov[nc] = ovl; cnr[nc] = nrm; ccur[nc] = 0.0lf; cft[nc] = 2u * ax + side;
                        nc++;
                    }
                }
            }
        } else if (u.x == 2u) {
            // cylinder, inside: g0 = base centre, g1 = unit axis, g2 = (radius, length)
            let rel = xb - g0.xyz;
            let a = dot(g1.xyz, rel);
            let rho = rel - g1.xyz * a;
            let rn = sqrt(norm2(rho));
            let dd = g2.x - rn;
            if (r - dd > 0.0lf) {
                var uu = vec3<f64>(1.0lf, 0.0lf, 0.0lf);
                if (rn > 0.0lf) {
                    uu = rho / rn;
                } else {
                    var tt = vec3<f64>(1.0lf, 0.0lf, 0.0lf);
                    if (abs(g1.x) >= 0.9lf) { tt = vec3<f64>(0.0lf, 1.0lf, 0.0lf); }
                    let pp = tt - g1.xyz * dot(g1.xyz, tt);
                    uu = pp / sqrt(norm2(pp));
                }
                cov[nc] = r - dd; cnr[nc] = -uu; ccur[nc] = -2.0lf * g2.x; cft[nc] = 0u; nc++;
            }
            if (r - a > 0.0lf) {
                cov[nc] = r - a; cnr[nc] = g1.xyz; ccur[nc] = 0.0lf; cft[nc] = 1u; nc++;
            }
            let dtop = g2.y - a;
            if (r - dtop > 0.0lf) {
                cov[nc] = r - dtop; cnr[nc] = -g1.xyz; ccur[nc] = 0.0lf; cft[nc] = 2u; nc++;
            }
        }
        for (var c = 0u; c < nc; c++) {
            let key = wall * 8u + cft[c];
            var k = 0xffffffffu;
            for (var o = 0u; o < wold; o++) {
                if (w_keys_in[kb + 1u + o] == key) { k = o; break; }
            }
            var s = zero_state();
            if (k != 0xffffffffu) {
                s = load_w(wb + k);
                wvisited = wvisited | (1u << k);
            }
            let nrm = cnr[c];
            let ovl = cov[c];
            var r_eff = r;
            if (ccur[c] != 0.0lf) { r_eff = 1.0lf / (1.0lf / r + 1.0lf / ccur[c]); }
            let li = info.x * P.n_mat + u.z;
            let rb = r - 0.5lf * max(ovl, 0.0lf);
            let v_p = vi.xyz + cross(wi, -rb * nrm);
            let v_rel = v_p - v_wall;
            let rate = -dot(nrm, vi.xyz - v_wall);
            let lo = contact_law(li, r_eff, mi, ovl, rate, nrm, tangential(v_rel, nrm), dt, &s);
            let fn_vec = nrm * (lo.el + lo.dis);
            let ft = lo.ft;
            let f_total = fn_vec + ft;
            work += 0.5lf * dot(s.fnp + s.ftp + f_total, v_wall) * dt;
            dn_pw += -0.5lf * dot(s.fnp + fn_vec, v_rel) * dt - (lo.en - s.enp);
            dt_pw += -0.5lf * dot(s.ftp + ft, v_rel) * dt - (lo.et - s.etp);
            elastic += lo.en + lo.et;
            f += f_total;
            t += cross(-rb * nrm, ft);
            load_f += f_total * flag;
            load_t += cross(xi.xyz - nrm * (r - ovl) - bpos, -f_total) * flag;
            s.fnp = fn_vec;
            s.ftp = ft;
            s.enp = lo.en;
            s.etp = lo.et;
            if (wm < P.max_wc) {
                w_keys_out[kb + 1u + wm] = key;
                store_w(wb + wm, s, nrm);
                wm++;
            } else {
                flag_error(ERR_WALL_CONTACTS, i);
            }
        }
    }
    // Wall contacts that ended: close their work integral.
    for (var o = 0u; o < wold; o++) {
        if ((wvisited & (1u << o)) != 0u) { continue; }
        let s = load_w(wb + o);
        let nrm = load_w_normal(wb + o);
        let wall = w_keys_in[kb + 1u + o] / 8u;
        let row = step * P.n_bodies + tab_u[P.off_wall_u + wall].y;
        let v_wall = tab_f[P.off_body + 2u * row + 1u].xyz;
        let v_rel = vi.xyz + cross(wi, -r * nrm) - v_wall;
        work += 0.5lf * dot(s.fnp + s.ftp, v_wall) * dt;
        dn_pw += -0.5lf * dot(s.fnp, v_rel) * dt + s.enp;
        dt_pw += -0.5lf * dot(s.ftp, v_rel) * dt + s.etp;
    }
    w_keys_out[kb] = wm;

    frc[i] = vec4<f64>(f, 0.0lf);
    trq[i] = vec4<f64>(t, 0.0lf);
    let lb = 6u * i;
    ledger[lb] += vec4<f64>(dn_pp, dt_pp, dn_pw, dt_pw);
    let l1 = ledger[lb + 1u];
    ledger[lb + 1u] = vec4<f64>(l1.x + work, elastic, 0.0lf, 0.0lf);
    // single-bin DFT of the load over the sampling window (trapezoid over the step)
    let q = wstep(step, world, 1u);
    if (any(q != vec4<f64>(0.0lf))) {
        let f_prev = ledger[lb + 2u].xyz;
        ledger[lb + 4u] += vec4<f64>(f_prev * q.x + load_f * q.z, 0.0lf);
        ledger[lb + 5u] += vec4<f64>(f_prev * q.y + load_f * q.w, 0.0lf);
    }
    ledger[lb + 2u] = vec4<f64>(load_f, 0.0lf);
    ledger[lb + 3u] = vec4<f64>(load_t, 0.0lf);
}

// Second half kick; non-finite states are flagged with the particle.
@compute @workgroup_size(256)
fn kick(@builtin(global_invocation_id) g: vec3<u32>) {
    let i = g.x;
    if (i >= P.n) { return; }
    let ws = wstep(atomicLoad(&ctrl[1]) - 1u, pinfo(i).y, 0u);
    if (ws.y == 0.0lf) { return; }
    let h = 0.5lf * ws.x;
    let v = vel[i];
    let w = omg[i];
    let v3 = v.xyz + frc[i].xyz * (h / v.w);
    let w3 = w.xyz + trq[i].xyz * (h * w.w);
    vel[i] = vec4<f64>(v3, v.w);
    omg[i] = vec4<f64>(w3, w.w);
    if (!(finite3(v3) && finite3(w3) && finite3(pos[i].xyz))) {
        flag_error(ERR_NONFINITE, i);
    }
}

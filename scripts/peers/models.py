"""The peer models of the side-by-side table, written from their formulations (sympy), and a
reader that evaluates the written Minibex and PHC text back in Python.

Each case gives its unknowns with their ranges, equations (= 0) and inequalities (>= 0) as sympy
expressions; `minibex` and `phc` turn them into `ibexsolve` and `phc -b` input. Numbers are
written with 20 significant digits. Geometry comes from the repository's files
(tests/data/stewart_6_6_fk.json, urdf/*.urdf, urdf/four_spheres.json) or, where the URDF states
it in its comment, from that statement (checked against linkspace's solutions by --check-models).
"""

import json
import math
import re
from pathlib import Path

import sympy as sp

ROOT = Path(__file__).resolve().parents[2]
DIGITS = 20
# Angle ranges: the double just above pi, so [-PI_UP, PI_UP] holds the whole circle.
PI_UP = math.nextafter(math.pi, 4.0)


def num(x):
    """A coefficient: exact decimal strings stay exact, floats keep their 17 digits."""
    if isinstance(x, str):
        return sp.Float(x, DIGITS)
    if isinstance(x, int):
        return sp.Integer(x)
    return sp.Float(repr(float(x)), DIGITS)


class Model:
    def __init__(self, name, variables, equations, inequalities=(), functions=(), note=""):
        self.name = name
        self.variables = variables  # [(symbol, lo, hi)]
        self.equations = list(equations)
        self.inequalities = list(inequalities)
        # Minibex functions: (name, [(local, expr)], result expr); the equation is name(vars) = 0.
        self.functions = list(functions)
        self.note = note

    @property
    def symbols(self):
        return [v[0] for v in self.variables]

    def all_equations(self):
        """Every equation as one sympy expression (functions inlined)."""
        eqs = list(self.equations)
        for _, defs, result in self.functions:
            expr = result
            for local, value in reversed(defs):
                expr = expr.subs(local, value)
            eqs.append(expr)
        return eqs

    def polynomial(self):
        return not self.functions and all(e.is_polynomial(*self.symbols) for e in self.equations)


def decimal(expr):
    """Exact rationals written as 20-digit decimals (phc reads no fractions)."""
    return expr.xreplace({r: sp.Float(r, DIGITS) for r in expr.atoms(sp.Rational) if not r.is_Integer})


def text(expr):
    return sp.sstr(decimal(expr), full_prec=False).replace("**", "^")


def minibex(model):
    out = [f"// {model.name}: {model.note}" if model.note else f"// {model.name}"]
    args = ", ".join(str(s) for s in model.symbols)
    for fname, defs, result in model.functions:
        out.append(f"function {fname}({args})")
        for local, value in defs:
            out.append(f"  {local} = {text(value)};")
        out.append(f"  return {text(result)};")
        out.append("end")
    out.append("Variables")
    for s, lo, hi in model.variables:
        out.append(f"  {s} in [{lo!r}, {hi!r}];")
    out.append("Constraints")
    for e in model.equations:
        out.append(f"  {text(e)} = 0;")
    for fname, _, _ in model.functions:
        out.append(f"  {fname}({args}) = 0;")
    for e in model.inequalities:
        out.append(f"  {text(e)} >= 0;")
    out.append("end")
    return "\n".join(out) + "\n"


def phc(model):
    eqs = model.all_equations()
    lines = [f"{len(eqs)} {len(model.symbols)}"]
    lines += [f" {text(sp.expand(e))};" for e in eqs]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- reading the written text back

_MATH = {"cos": math.cos, "sin": math.sin, "sqrt": math.sqrt, "atan2": math.atan2, "pi": math.pi}


def _py(expr):
    return expr.replace("^", "**")


def eval_minibex(source, point):
    """The residuals of the written Minibex model at `point` (a dict name -> float): equations
    first (lhs - rhs), then inequalities (lhs - rhs, to be >= 0)."""
    functions = {}
    for m in re.finditer(r"function (\w+)\(([^)]*)\)\n(.*?)\nend", source, re.S):
        params = [p.strip() for p in m.group(2).split(",")]
        functions[m.group(1)] = (params, [l.strip().rstrip(";") for l in m.group(3).splitlines()])

    def call(fname):
        params, body = functions[fname]

        def f(*args):
            env = dict(_MATH, **dict(zip(params, args)))
            for stmt in body:
                if stmt.startswith("return "):
                    return eval(_py(stmt[7:]), {}, env)
                local, value = stmt.split("=", 1)
                env[local.strip()] = eval(_py(value), {}, env)
            raise ValueError(f"{fname}: no return")

        return f

    env = dict(_MATH, **point, **{n: call(n) for n in functions})
    block = source.split("Constraints", 1)[1].rsplit("end", 1)[0]
    equations, inequalities = [], []
    for line in block.strip().splitlines():
        line = line.strip().rstrip(";")
        if ">=" in line:
            lhs, rhs = line.split(">=")
            inequalities.append(eval(_py(lhs), {}, env) - eval(_py(rhs), {}, env))
        else:
            lhs, rhs = line.split("=")
            equations.append(eval(_py(lhs), {}, env) - eval(_py(rhs), {}, env))
    return equations, inequalities


def minibex_domain(source):
    return {m.group(1): (float(m.group(2)), float(m.group(3)))
            for m in re.finditer(r"^\s*(\w+) in \[([^,]+), ([^\]]+)\];", source, re.M)}


def eval_phc(source, point):
    lines = source.strip().splitlines()[1:]
    env = dict(point)
    return [eval(_py(l.strip().rstrip(";")), {}, env) for l in lines]


# ---------------------------------------------------------------- geometry helpers


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def norm2(a):
    return dot(a, a)


def qmul(p, q):
    a0, a1, a2, a3 = p
    b0, b1, b2, b3 = q
    return [a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0]


def rot_from_quaternion(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def rodrigues(axis, c, s):
    """The rotation about the unit `axis` with cos c, sin s (sympy or float entries)."""
    x, y, z = axis
    C = 1 - c
    return [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
            [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
            [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]


def matvec(m, v):
    return [sum(m[i][j] * v[j] for j in range(3)) for i in range(3)]


def _origin(element):
    """xyz and rpy of the first <origin .../> in `element` (attributes in any order)."""
    m = re.search(r"<origin([^>]*)/>", element)
    attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(1))) if m else {}
    return ([float(v) for v in attrs.get("xyz", "0 0 0").split()], [float(v) for v in attrs.get("rpy", "0 0 0").split()])


def urdf_origins(path):
    """name -> (xyz, rpy) of every <joint> origin, and of every loop's predecessor and successor
    origins (as "loop.predecessor", "loop.successor")."""
    xml = Path(path).read_text()
    out = {}
    for m in re.finditer(r'<joint name="(\w+)"(.*?)</joint>', xml, re.S):
        out[m.group(1)] = _origin(m.group(2))
    for m in re.finditer(r'<loop name="(\w+)"(.*?)</loop>', xml, re.S):
        for side in ("predecessor", "successor"):
            part = re.search(rf"<{side}(.*?)</{side}>", m.group(2), re.S)
            out[f"{m.group(1)}.{side}"] = _origin(part.group(1))
    return out


# ---------------------------------------------------------------- the cases


def stewart_data():
    return json.loads((ROOT / "tests/data/stewart_6_6_fk.json").read_text())


def stewart_case(data, case="from_pose"):
    c = next(c for c in data["cases"] if c["name"] == case)
    lengths = [c["leg_lengths"][f"leg{i}"] for i in range(1, 7)]
    return data["base_ball_centres"], data["platform_ball_centres_in_platform_frame"], lengths, c


def stewart_ibex(data):
    base, plat, lengths, _ = stewart_case(data)
    a = sp.symbols("a1:4")
    b = sp.symbols("b1:4")
    t = sp.symbols("t1:4")
    c = cross(a, b)
    eqs = [a[0] ** 2 + a[1] ** 2 + a[2] ** 2 - 1, b[0] ** 2 + b[1] ** 2 + b[2] ** 2 - 1,
           a[0] * b[0] + a[1] * b[1] + a[2] * b[2]]
    for B, P, L in zip(base, plat, lengths):
        comps = [t[k] + num(P[0]) * a[k] + num(P[1]) * b[k] + num(P[2]) * c[k] - num(B[k]) for k in range(3)]
        eqs.append(sum(x ** 2 for x in comps) - num(L) ** 2)
    variables = [(s, -1.0, 1.0) for s in a + b] + [(s, -2.2, 2.2) for s in t]
    return Model("stewart_from_pose", variables, eqs,
                 note="rotation columns a, b (c = a x b inlined) and position t; six legs (9 x 9)")


# A fixed real normalisation of the Study rotation part (x . N = 1): any generic choice works.
STUDY_NORMAL = ["0.7310585786300049", "-0.2689414213699951", "0.4621171572600098", "0.8807970779778823"]


def stewart_phc(data):
    base, plat, lengths, _ = stewart_case(data)
    x = sp.symbols("x0:4")  # rotation part (quaternion, scaled)
    y = sp.symbols("y0:4")  # translation part: t = 2 y conj(x) / |x|^2
    eqs = []
    for B, P, L in zip(base, plat, lengths):
        xp = qmul(x, [0, num(P[0]), num(P[1]), num(P[2])])
        bx = qmul([0, num(B[0]), num(B[1]), num(B[2])], x)
        v = [xp[k] - bx[k] + 2 * y[k] for k in range(4)]
        eqs.append(sum(w ** 2 for w in v) - num(L) ** 2 * sum(w ** 2 for w in x))
    eqs.append(sum(x[k] * y[k] for k in range(4)))
    eqs.append(sum(num(n) * x[k] for k, n in enumerate(STUDY_NORMAL)) - 1)
    return Model("stewart_from_pose", [(s, -10.0, 10.0) for s in x + y], eqs,
                 note="Study parameters: |x p - b x + 2 y|^2 = L^2 |x|^2, x . y = 0, one linear normalisation of x")


def stewart_references(data):
    """(Ibex point, PHC point) per real assembly of the JSON."""
    _, _, _, case = stewart_case(data)
    refs = []
    for s in case["solutions"]:
        R = s["platform_rotation_matrix"]
        t = s["platform_position"]
        ibex = {f"a{k + 1}": R[k][0] for k in range(3)}
        ibex.update({f"b{k + 1}": R[k][1] for k in range(3)})
        ibex.update({f"t{k + 1}": t[k] for k in range(3)})
        q = [float(v) for v in s["platform_quaternion_wxyz"]]
        scale = sum(float(n) * q[k] for k, n in enumerate(STUDY_NORMAL))
        xq = [v / scale for v in q]
        yq = [v / 2 for v in qmul([0.0] + t, xq)]
        phcp = {f"x{k}": xq[k] for k in range(4)}
        phcp.update({f"y{k}": yq[k] for k in range(4)})
        refs.append((ibex, phcp))
    return refs


OCTAHEDRAL_FIXED = {
    "a": {"leg15": 4.25, "leg16": 5.75, "leg26": 4.25, "leg24": 5.75, "leg34": 4.25, "leg35": 5.75},
    "b": {leg: 4.75 for leg in ["leg15", "leg16", "leg26", "leg24", "leg34", "leg35"]},
}


def octahedral(which):
    o = urdf_origins(ROOT / "urdf/octahedral.urdf")
    base = {"1": o["leg15_base"][0], "2": o["leg26_base"][0], "3": o["leg34_base"][0]}
    p = {k: sp.symbols(f"p{k}x p{k}y p{k}z") for k in "456"}
    eqs = [sum((p[i][k] - p[j][k]) ** 2 for k in range(3)) - num(0.75) for i, j in [("4", "5"), ("5", "6"), ("6", "4")]]
    for leg, sq in OCTAHEDRAL_FIXED[which].items():
        b, q = leg[3], leg[4]
        eqs.append(sum((p[q][k] - num(base[b][k])) ** 2 for k in range(3)) - num(sq))
    variables = [(s, -5.0, 5.0) for k in "456" for s in p[k]]
    return Model(f"octahedral_{which}", variables, eqs,
                 note="platform points p4, p5, p6; three sides^2 = 0.75 and six squared legs (9 x 9)")


def octahedral_platform_points(pose):
    """p4, p5, p6 (URDF: platform frame points of the loops) from a linkspace pose."""
    o = urdf_origins(ROOT / "urdf/octahedral.urdf")
    local = {"4": o["leg24_top.successor"][0], "5": o["leg15_top.successor"][0], "6": o["leg16_top.successor"][0]}
    R = rot_from_quaternion(pose["quaternion"])
    pt = {}
    for k, v in local.items():
        w = [a + b for a, b in zip(matvec(R, v), pose["position"])]
        pt.update({f"p{k}x": w[0], f"p{k}y": w[1], f"p{k}z": w[2]})
    return pt


def four_spheres():
    spec = json.loads((ROOT / "urdf/four_spheres.json").read_text())
    c = {p["name"]: p["xyz"] for p in spec["points"] if "xyz" in p}
    r2 = spec["distances"][0]["squared"]
    x = sp.symbols("x1:4")
    d = sp.symbols("d1:4")
    t = [num(c["c1"][k]) + x[k] for k in range(3)]
    eqs = [sum(v ** 2 for v in x) - num(r2), sum(v ** 2 for v in d) - 1, sum(x[k] * d[k] for k in range(3))]
    for pl in spec["point_line"]:
        w = [num(c[pl["point"]][k]) - t[k] for k in range(3)]
        eqs.append(sum(v ** 2 for v in w) - sum(w[k] * d[k] for k in range(3)) ** 2 - num(pl["squared"]))
    toward = [num(c["c2"][k]) - t[k] for k in range(3)]
    ineq = [sum(d[k] * toward[k] for k in range(3))]
    variables = [(s, -2.0, 2.0) for s in x] + [(s, -1.0, 1.0) for s in d]
    return Model("four_spheres", variables, eqs, ineq,
                 note="t = c1 + x on the line, direction d; |x|^2, |d|^2 = 1, x.d = 0, three point-line distances^2; d.(c2 - t) >= 0")


DELTA_FIXED = {"actuator1": 0.2, "actuator2": 0.75, "actuator3": -0.1}


def delta():
    o = urdf_origins(ROOT / "urdf/delta.urdf")
    P = sp.symbols("px py pz")
    eqs = []
    for i in (1, 2, 3):
        a_xyz, a_rpy = o[f"actuator{i}"]
        yaw = a_rpy[2]
        arm = o[f"elbow{i}"][0][0]
        forearm = -o[f"wrist{i}.predecessor"][0][2]
        wrist = o[f"wrist{i}.successor"][0]
        q = DELTA_FIXED[f"actuator{i}"]
        local = [arm * math.cos(q), 0.0, -arm * math.sin(q)]
        elbow = [a_xyz[0] + math.cos(yaw) * local[0] - math.sin(yaw) * local[1],
                 a_xyz[1] + math.sin(yaw) * local[0] + math.cos(yaw) * local[1],
                 a_xyz[2] + local[2]]
        eqs.append(sum((P[k] + num(wrist[k]) - num(elbow[k])) ** 2 for k in range(3)) - num(forearm) ** 2)
    return Model("delta", [(s, -1.5, 1.5) for s in P], eqs,
                 note="platform position; three sphere equations (forearm from elbow to wrist)")


SPHERICAL_CRANK = 0.4


def spherical_four_bar(angles=True):
    xml = (ROOT / "urdf/spherical_four_bar.urdf").read_text()
    axis = {m.group(1): [float(v) for v in m.group(2).split()]
            for m in re.finditer(r'<joint name="(\w+)".*?<axis xyz="([^"]+)"', xml, re.S)}
    o = urdf_origins(ROOT / "urdf/spherical_four_bar.urdf")
    pitch = [o["loop_coupler_rocker.predecessor"][1][1], o["loop_coupler_rocker.successor"][1][1]]
    if angles:
        c, r = sp.symbols("coupler rocker")
        cc, sc, cr, sr = sp.cos(c), sp.sin(c), sp.cos(r), sp.sin(r)
        variables = [(c, -PI_UP, PI_UP), (r, -PI_UP, PI_UP)]
    else:
        cc, sc, cr, sr = sp.symbols("cc sc cr sr")
        variables = [(s, -1.0, 1.0) for s in (cc, sc, cr, sr)]
    t = SPHERICAL_CRANK
    crank = [[num(math.cos(t)), -num(math.sin(t)), 0], [num(math.sin(t)), num(math.cos(t)), 0], [0, 0, 1]]
    u2 = [num(v) for v in axis["coupler_joint"]]
    u4 = [num(v) for v in axis["rocker_joint"]]
    ez_pre = [num(math.sin(pitch[0])), 0, num(math.cos(pitch[0]))]  # Ry(1.4) z in the coupler frame
    ez_suc = [num(math.sin(pitch[1])), 0, num(math.cos(pitch[1]))]  # Ry(1.8) z in the rocker frame
    u3_c = matvec(crank, matvec(rodrigues(u2, cc, sc), ez_pre))
    u3_r = matvec(rodrigues(u4, cr, sr), ez_suc)
    eqs = [sp.expand(u3_c[1] - u3_r[1]), sp.expand(u3_c[2] - u3_r[2])]
    ineq = [sp.expand(u3_c[0] * u3_r[0])]
    if not angles:
        eqs += [cc ** 2 + sc ** 2 - 1, cr ** 2 + sr ** 2 - 1]
    return Model("spherical_four_bar", variables, eqs, ineq,
                 note=f"crank {t}: coupler and rocker angles; the closing axis from both sides, y and z equal, x of one sign")


BUTTERFLY_THETA6 = "atan2(12, 5)"


def butterfly(angles=True):
    # The paper's parameters (research notes): every angle is a rational direction.
    a0, b0 = 7, 13
    g0 = (sp.Rational(4, 5), sp.Rational(3, 5))       # gamma0 = atan2(3, 4)
    a1, b1, g1 = 7, 6, (sp.Rational(12, 13), sp.Rational(5, 13))
    a2, b2, g2 = 5, 3, (sp.Rational(3, 5), sp.Rational(4, 5))
    b6, c6, e6 = 3, 2, (sp.Rational(4, 5), sp.Rational(3, 5))
    l3, l4, l5, l7 = 7, 9, 12, 11
    names = [1, 2, 3, 4, 5, 7]
    u = {6: (sp.Rational(5, 13), sp.Rational(12, 13))}
    if angles:
        th = {i: sp.Symbol(f"th{i}") for i in names}
        u.update({i: (sp.cos(th[i]), sp.sin(th[i])) for i in names})
        variables = [(th[i], -PI_UP, PI_UP) for i in names]
    else:
        cs = {i: sp.symbols(f"c{i} s{i}") for i in names}
        u.update(cs)
        variables = [(s, -1.0, 1.0) for i in names for s in cs[i]]

    def rot(g, v):
        return (g[0] * v[0] - g[1] * v[1], g[1] * v[0] + g[0] * v[1])

    def lin(*terms):
        return [sum(k * v[j] for k, v in terms) for j in range(2)]

    A = lin((l7, u[7]), (a2, u[2]), (a1, u[1]), (-l5, u[5]), (1, (b0, 0)))
    B = lin((l7, u[7]), (a2, u[2]), (b1, rot(g1, u[1])), (-l3, u[3]), (-c6, rot(e6, u[6])), (a0, (g0[0], -g0[1])))
    C = lin((l7, u[7]), (b2, rot(g2, u[2])), (-l4, u[4]), (-b6, u[6]), (a0, (g0[0], -g0[1])))
    eqs = [sp.expand(e) for e in A + B + C]
    if not angles:
        eqs += [cs[i][0] ** 2 + cs[i][1] ** 2 - 1 for i in names]
    return Model("butterfly_rigid", variables, eqs,
                 note="theta6 = atan2(12, 5); loops A, B, C of the double butterfly (two rows each)")


RPR_RHO3 = 17


def det3(m):
    """The determinant by cofactors, unexpanded (common subexpressions stay visible to cse)."""
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def three_rpr():
    """The cusp system at rho3 = 17 in the pose (x, y of B1, platform angle phi), derived
    exactly (the URDF's decimals as rationals) and written with shared subexpressions."""
    o = urdf_origins(ROOT / "urdf/three_rpr.urdf")
    exact = lambda v: sp.Rational(repr(v))
    A = [[exact(v) for v in o[f"a{i}_joint"][0][:2]] for i in (1, 2, 3)]
    v2 = [exact(v) for v in o["b2.predecessor"][0][:2]]
    v3 = [exact(v) for v in o["b3.predecessor"][0][:2]]
    x, y, phi = sp.symbols("x y phi")
    c, s = sp.cos(phi), sp.sin(phi)
    B = [(x, y), (x + v2[0] * c - v2[1] * s, y + v2[0] * s + v2[1] * c),
         (x + v3[0] * c - v3[1] * s, y + v3[0] * s + v3[1] * c)]
    rho2 = [(B[i][0] - A[i][0]) ** 2 + (B[i][1] - A[i][1]) ** 2 for i in range(3)]
    X = [x, y, phi]
    g = rho2[2] - RPR_RHO3 ** 2
    grad = lambda f: [sp.diff(f, v) for v in X]
    D = det3([grad(g), grad(rho2[0]), grad(rho2[1])])
    G1 = det3([grad(rho2[0]), grad(g), grad(D)])
    functions = []
    for fname, expr in (("det_d", D), ("cusp_g1", G1)):
        defs, (result,) = sp.cse(expr, symbols=sp.numbered_symbols("w"))
        functions.append((fname, defs, result))
    return Model("three_rpr_cusps", [(x, -40.0, 40.0), (y, -40.0, 40.0), (phi, -PI_UP, PI_UP)], [g],
                 functions=functions,
                 note="rho3 = 17: g = rho3^2 - 17^2, D = det[grad g; grad rho1^2; grad rho2^2], G1 = det[grad rho1^2; grad g; grad D]")

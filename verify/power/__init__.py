"""python -m verify.power: the detection power of `garant diagnose`, measured on sets made here.

Each set: a unit with random errors (small: every stand and block error up to 1e-4; MEMS-size: scale
errors up to 1e-2, misalignments up to 1e-2 rad, biases up to 5e-2 g, mounting up to 3e-3 rad, stand
errors up to 2e-5 rad), read at the positions of a plan in a random order (the time and temperature of
each row follow the order), with noise bounded by sigma (uniform over the band, or Gaussian with
standard deviation sigma/3 clipped at sigma: the band is rarely touched). A catalogue effect is hidden
in a random direction of its parameters, scaled to a signature of a x sigma (the largest change of a
reading it makes, over the positions, in units of sigma). `diagnose` runs with the whole catalogue and
its default premises (a local g). A set counts as named when the effect is chosen or tied with the one
chosen (indistinguishable on the plan); a spurious effect is one chosen that is neither hidden nor tied.

    python -m verify.power [--sets N] [--levels 1,1.5,2,3] [--setup two-axis:grid:30x45,...] [--units small,MEMS]
                           [--net]                            detection rate per effect, level, setup; --net:
                                                              levels of the part the model cannot absorb
    python -m verify.power --pairs [--sets N] [--net]         two effects at 2 sigma: exactly those two named
    python -m verify.power --clean N                          false alarms of diagnose on N clean sets
    python -m verify.power --mems                             MEMS-size units, estimate
    python -m verify.power --mems-stands [--sets N]           MEMS-size truths on every built-in stand,
                                                              random and adversarial: soundness, non-vacuity
    python -m verify.power --information [--sets N]           what the readings prove against what the
                                                              plan guarantees, on 10 / 24 / 96 / 288 positions
"""
import sys

import numpy as np

from ..outcomes import Status

SIGMA, G = 1e-5, 9.81
#: (stand, plan) of the study: the 24- and 96-position grids of the two-axis stand, the single-axis table.
SETUPS = (("two-axis", "grid:90x60"), ("two-axis", "grid:30x45"), ("single-axis", "grid:30"))
LEVELS = (1.0, 1.5, 2.0, 3.0)
NOISES = ("uniform", "clipped")
#: Error sizes by parameter kind (block: scale errors on the diagonal, misalignments off it), and mounting.
SIZES = {"small": {"stand": 1e-4, "scale": 1e-4, "misalignment": 1e-4, "bias": 1e-4, "mounting": 1e-4},
         "MEMS": {"stand": 2e-5, "scale": 1e-2, "misalignment": 1e-2, "bias": 5e-2, "mounting": 3e-3}}


class Lab:
    """Exact modules of the extended models of one stand (rendered once each) and its plans."""

    def __init__(self, stand):
        from .. import models
        self.name, self.base, self.mod = stand, models.stand_model(stand), models.load(stand)

    def exact(self, effects):
        """The rendered module of the stand with these effects (simulate.exact_module, which keeps it)."""
        from garant.derive import effects as catalogue
        from ..workflows import simulate
        return simulate.exact_module(catalogue.extend(self.base, sorted(effects)))

    def unit(self, size, rng):
        """Random values of the base model's parameters, by kind, within SIZES[size]."""
        kinds = dict(zip(self.mod.PARAMETER_NAMES, self.mod.PARAMETER_KINDS))
        out = {}
        for p in self.base.parameters:
            kind = kinds.get(p.name, "stand")
            if kind == "block":
                kind = "scale" if p.name[-1] == p.name[-2] else "misalignment"
            out[p.name] = 0.0 if kind == "gravity" else rng.uniform(-1, 1) * SIZES[size][kind]
        return out

    def signature(self, change, P, mounts, net):
        """An effect's size in sigma from its change of the readings (N, 3) in g: the largest change of a
        reading, or (`net`) the part the current model cannot absorb, the minimax residual after the best q."""
        if not net:
            return np.abs(change).max() / SIGMA
        from ..solve import highs, lp
        return highs.chebyshev_fit(lp.measurement_matrix(self.mod, np.deg2rad(P), mounts),
                                   change.reshape(-1))[1] / SIGMA

    def readings(self, effects, values, P, mounts, t, T):
        """Exact readings (N, 3) in m/s^2 with these effect values (name -> values) added to `values`."""
        from garant.derive.effects import CATALOGUE
        exact = self.exact(list(effects))
        v = dict(values)
        for name, vals in effects.items():
            v.update(zip((p.name for p in CATALOGUE[name].params), vals))
        physical = [v[n] for n in exact.PARAMETER_NAMES]
        kw = {k: x for k, x in (("time_s", t), ("temp_c", T)) if k in exact.readings.__code__.co_varnames}
        if mounts is None:
            return exact.readings(*np.deg2rad(P).T, physical, G, **kw).T
        return np.column_stack([exact.readings(*np.deg2rad(P[k]), physical, G, mount=int(mounts[k]),
                                               **{n: x[k] for n, x in kw.items()}) for k in range(len(P))]).T


def make_set(lab, plan, size, hidden, noise, seed, net=False):
    """Positions of one simulated set: hidden is {effect: signature in sigma}, each in a random direction
    of its parameters; the positions in a random order; noise 'uniform' or 'clipped'. With `net`, the
    signature is the part of the effect's change the current model cannot absorb: its minimax residual
    after the best q (the LP of the verdict), not its largest change of a reading."""
    from garant.derive.effects import CATALOGUE

    from ..io.positions import Positions
    from ..workflows import simulate
    rng = np.random.default_rng(seed)
    P, mounts = simulate.plan_positions(lab.mod, plan)
    order = rng.permutation(len(P))
    P, mounts = P[order], (None if mounts is None else mounts[order])
    t, T = simulate.rows_time_temp(len(P))
    values = lab.unit(size, rng)
    f0 = lab.readings({}, values, P, mounts, t, T)
    effects = {}
    for name, a in hidden.items():
        d = rng.normal(size=len(CATALOGUE[name].params))
        d /= np.linalg.norm(d)
        signature = lab.signature((lab.readings({name: d}, values, P, mounts, t, T) - f0) / G, P, mounts, net)
        effects[name] = a / signature * d          # the readings are linear in an effect's parameters
    f = lab.readings(effects, values, P, mounts, t, T)
    if noise == "uniform":
        f = f + G * SIGMA * rng.uniform(-1, 1, f.shape)
    else:
        f = f + G * SIGMA * np.clip(rng.normal(0, 1 / 3, f.shape), -1, 1)
    extra = {"time_s": [f"{x:g}" for x in t], "temp_c": [f"{x:.4f}" for x in T]}
    return Positions(f"set {seed}", P, f, mounts, extra)


def diagnosis(lab, positions):
    """`diagnose` on a set with its default premises and a local g: (named, tied: the effects tied with a
    named one, the current model consistent, the effects the plan is blind to)."""
    from ..workflows import diagnose
    from ..workflows.premises import premises
    res = diagnose.diagnose(lab.base, lab.mod, positions, SIGMA, premises(lab.mod, SIGMA, G))
    return (set(res["effects"]), {e for g in res["indistinguishable"] for e in g}, res["consistent_before"],
            res["blind_to"])


def outcome(lab, positions, hidden):
    """(every hidden effect named or tied, a spurious effect named, the current model refuted) for one set.
    Where the data do not refute the current model (the effect's change hides in what the model absorbs),
    no test that keeps its false-alarm promise can name anything."""
    named, tied, consistent, _ = diagnosis(lab, positions)
    found = all(e in named or e in tied for e in hidden)
    spurious = any(e not in hidden and not (e in tied and tied & set(hidden)) for e in named)
    return found, spurious, not consistent


def rates(sets, levels, setups=SETUPS, progress=print, net=False, sizes=tuple(SIZES)):
    """Rows (stand, plan, size, effect, level, named %, spurious %, refuted %) over `sets` sets per cell, each
    set with its own unit, direction, order and noise (half uniform, half clipped Gaussian); refuted: the
    sets whose data refute the current model at all. `net`: levels of the part the model cannot absorb."""
    from garant.derive import effects as catalogue
    rows = []
    for stand, plan in setups:
        lab = Lab(stand)
        blind = diagnosis(lab, make_set(lab, plan, "small", {}, "uniform", 0))[3]
        for e in blind:           # diagnose says so (blind_to); scaled to a signature, it would be enormous
            progress(f"{stand}  {plan}  {e}: the plan is blind to it (first order), not tried")
        for size in sizes:
            for effect in [e for e in catalogue.applicable(lab.base) if e not in blind]:
                for a in levels:
                    res = [outcome(lab, make_set(lab, plan, size, {effect: a}, NOISES[k % 2], 7919 * k + 13, net),
                                   {effect})
                           for k in range(sets)]
                    rows.append((stand, plan, size, effect, a,
                                 *(100.0 * np.mean([r[i] for r in res]) for i in range(3))))
                    progress("  ".join(f"{x:g}" if isinstance(x, float) else str(x) for x in rows[-1]))
    return rows


def clean_alarms(n, stand="two-axis", plan="grid:30x45"):
    """False alarms of diagnose (the current model called inconsistent, or any effect named) on n clean
    sets, half small and half MEMS-size units, half uniform and half clipped noise."""
    lab = Lab(stand)
    alarms = 0
    for k in range(n):
        named, _, consistent, _ = diagnosis(lab, make_set(lab, plan, list(SIZES)[k % 2], {}, NOISES[(k // 2) % 2], k))
        alarms += bool(named) or not consistent
    return alarms


def mems_sets(sets=10, mounting=5e-3, stand=2e-5):
    """The MEMS-size study, per set: (consistent, largest guaranteed error, largest |q - q_true| / bound). A
    MEMS-size block (scale errors to 2e-2, misalignments to 1e-2, biases to 0.1 g, mounting to 5e-3 rad) on
    the 30 x 45 degree grid of the two-axis stand, stand errors to 2e-5 rad, g exact with a local --g, noise
    at +-sigma with random signs, the premises' defaults. q_true is that of the unit with the mounting and
    Delta_g absorbed into Gamma (models.q_of), the q an estimate bounds."""
    from .. import models
    from ..io.positions import Positions
    from ..workflows.estimate import estimate
    mod = models.load("two-axis")
    P = np.array([(a, b) for a in range(0, 360, 30) for b in range(0, 360, 45)], float)
    size = {"block": lambda n: 2e-2 if n[-1] == n[-2] else 1e-2, "bias": lambda n: 0.1,
            "mounting": lambda n: mounting, "stand": lambda n: stand, "gravity": lambda n: 0.0}
    rows = []
    for seed in range(sets):
        rng = np.random.default_rng(seed)
        p = np.array([rng.uniform(-1, 1) * size[k](n) for n, k in zip(mod.PARAMETER_NAMES, mod.PARAMETER_KINDS)])
        f = mod.readings(*np.deg2rad(P).T, p, G).T + G * SIGMA * rng.choice([-1.0, 1.0], (len(P), 3))
        r = estimate(mod, Positions("mems", P, f), SIGMA, G)
        if not r["consistent"]:
            rows.append((False, None, None))
            continue
        e = np.array(list(r["guaranteed_error"].values()))
        q = np.array(list(r["q"].values()))
        rows.append((True, float(e.max()), float((np.abs(q - models.q_of(mod, p)) / e).max())))
    return rows


#: A MEMS-size block: scale errors to 2e-2, misalignments to 1e-2 rad, biases to 0.1 g.
MEMS_BLOCK = {"scale": 2e-2, "misalignment": 1e-2, "bias": 0.1}
#: The 3-axis MEMS sweep's stands.
MEMS_STANDS = ("two-axis", "single-axis", "three-axis")


def mems_truth(mod, rng, block=MEMS_BLOCK, vertex=False):
    """Physical errors: the block's of the given size, the stand's, the mounting's and Delta_g/g within the bounds
    the premises state for the unit itself (`Premises.physical`: also where the block absorbs them), uniform
    inside or at a vertex of the box (where worst cases live)."""
    from ..workflows.premises import premises
    prem = premises(mod, SIGMA, G)
    bounds = prem.physical()
    draw = (lambda b: b * rng.choice([-1.0, 1.0])) if vertex else (lambda b: rng.uniform(-b, b))
    p = np.zeros(len(mod.PARAMETER_NAMES))
    for k, (name, kind) in enumerate(zip(mod.PARAMETER_NAMES, prem.kinds)):
        if kind == "block":
            p[k] = draw(block["scale"] if name[-1] == name[-2] else block["misalignment"])
        else:
            p[k] = draw(block["bias"] if kind == "bias" else bounds[k])
    return p


def mems_grid(mod):
    """(positions in degrees, mounting index per row or None): the 30 x 45 degree grid on two angles,
    90 degrees on three, 30 on one (in every mounting)."""
    from .. import models
    names, mounts = models.layout(mod)
    steps = {1: [30.0], 2: [30.0, 45.0], 3: [90.0] * 3}[len(names)]
    P = np.array(np.meshgrid(*[np.arange(0, 360, s) for s in steps], indexing="ij")).reshape(len(names), -1).T
    if len(mounts) == 1:
        return P, None
    return np.tile(P, (len(mounts), 1)), np.repeat(np.arange(len(mounts)), len(P))


def mems_readings(mod, P, m, p, noise):
    """Readings (m/s^2) of the unit p at P (mountings m) plus noise (units of g)."""
    kw = {"mount": m} if m is not None else {}
    return mod.readings(*np.deg2rad(P).T, p, G, **kw).T + G * noise


def mems_run(mod, P, m, f):
    """(result, q, guaranteed errors) of estimate on these readings with a local g; q and errors None if refuted."""
    from ..io.positions import Positions
    from ..workflows.estimate import estimate
    r = estimate(mod, Positions("mems", P, f, m), SIGMA, G)
    if not r["consistent"]:
        return r, None, None
    return r, np.array(list(r["q"].values())), np.array(list(r["guaranteed_error"].values()))


def estimator_weights(mod, P, m, f, nu):
    """The weights of q_nu's estimator on these readings: by linearity, the response of the estimate to a
    unit change of each reading is the estimator itself, read off the LP at the relinearised model."""
    from ..io.positions import Positions
    from ..solve import lp
    from ..workflows import estimate as workflow, guarantee
    from ..workflows.premises import premises
    pos = Positions("mems", P, f, m)
    z = workflow.residuals_table_axes(mod, pos, G, np.eye(3)).reshape(-1)
    A = lp.measurement_matrix(mod, np.deg2rad(P), m)
    return lp.primal(guarantee.linearise(mod, pos, z, A, premises(mod, SIGMA, G)).A)[0].T[nu]


def mems_sweep(name, sets=20, seed=2311):
    """The Monte Carlo plus adversarial check on one stand: MEMS-size truths (`mems_truth`), the first half
    of the sets drawn inside the box, the rest at its vertices, noise at +-sigma with random signs, then with
    the signs of the estimator of the largest bound (its worst case). Returns (runs, consistent, truths
    outside a printed bound, ratios of each run's largest bound over the same run's with block errors of
    1e-4, the largest over the q: not vacuous)."""
    from .. import models
    mod = models.load(name)
    P, m = mems_grid(mod)
    rng = np.random.default_rng(seed)
    small = {"scale": 1e-4, "misalignment": 1e-4, "bias": 1e-4}
    runs = consistent = outside = 0
    ratios = []
    for k in range(sets):
        p = mems_truth(mod, rng, vertex=k >= sets // 2)
        noise = rng.choice([-1.0, 1.0], (len(P), 3)) * SIGMA
        cases = [mems_run(mod, P, m, mems_readings(mod, P, m, p, noise))]
        if cases[0][0]["consistent"]:
            W = estimator_weights(mod, P, m, mems_readings(mod, P, m, p, 0 * noise), int(np.argmax(cases[0][2])))
            cases.append(mems_run(mod, P, m, mems_readings(mod, P, m, p, SIGMA * np.sign(W).reshape(-1, 3))))
        e_small = a_priori(mems_run(mod, P, m, mems_readings(mod, P, m, mems_truth(mod, rng, small), noise))[0])
        for r, q, e in cases:
            runs += 1
            if r["consistent"]:
                consistent += 1
                outside += int(np.any(np.abs(q - models.q_of(mod, p)) > e)) + int(np.any(e > a_priori(r)))
                ratios.append(float((a_priori(r) / e_small).max()))
    return runs, consistent, outside, ratios


def a_priori(r):
    """The a-priori guaranteed errors of an estimate's result (what the plan guarantees), over Q_NAMES."""
    return np.array(list(r["a_priori"]["guaranteed_error"].values()))


#: The information study's plans, (label, positions in degrees): the optimal plan of 000 and grids.
INFORMATION_PLANS = (("10 (optimal, Table 2 of 000)", None), ("24 (90 x 60)", (90, 60)), ("96 (30 x 45)", (30, 45)),
                     ("288 (15 x 30)", (15, 30)))


def information(sets=5, seed=40):
    """The information study: on the two-axis stand, small units (every error up to 1e-4), noise uniform in +-sigma or
    Gaussian with sd sigma/3 clipped at sigma: per plan and noise, the median over sets and q of the printed
    bound (what the readings prove) over the a-priori one (what the plan guarantees), the median printed bound
    in sigma, and the truths outside a printed bound. Rows (plan, noise, ratio, bound/sigma, outside, runs)."""
    from .. import models
    mod = models.load("two-axis")
    rng = np.random.default_rng(seed)
    rows = []
    for label, step in INFORMATION_PLANS:
        P = (np.asarray(mod.PLAN_DEG, float) if step is None else
             np.array([(a, b) for a in np.arange(0, 360, step[0]) for b in np.arange(0, 360, step[1])], float))
        for noise in NOISES:
            ratio, bound, outside = [], [], 0
            for _ in range(sets):
                p = rng.uniform(-1e-4, 1e-4, len(mod.PARAMETER_NAMES))
                e = (rng.uniform(-1, 1, (len(P), 3)) if noise == "uniform"
                     else np.clip(rng.normal(0, 1 / 3, (len(P), 3)), -1, 1)) * SIGMA
                r, q, err = mems_run(mod, P, None, mems_readings(mod, P, None, p, e))
                ratio += list(err / a_priori(r))
                bound += list(err / SIGMA)
                outside += int(np.any(np.abs(q - models.q_of(mod, p)) > err))
            rows.append((label, noise, float(np.median(ratio)), float(np.median(bound)), outside, sets))
    return rows


def pairs(sets, a=2.0, stand="two-axis", plan="grid:30x45", progress=print, net=False):
    """Two effects at a x sigma each: per pair, the % of sets where exactly those two are named (or tied)."""
    import itertools

    from garant.derive import effects as catalogue
    lab = Lab(stand)
    rows = []
    blind = diagnosis(lab, make_set(lab, plan, "small", {}, "uniform", 0))[3]
    for e1, e2 in itertools.combinations([e for e in catalogue.applicable(lab.base) if e not in blind], 2):
        hits = 0
        for k in range(sets):
            size, noise = list(SIZES)[k % 2], NOISES[(k // 2) % 2]
            found, spurious, _ = outcome(lab, make_set(lab, plan, size, {e1: a, e2: a}, noise, 104729 * k + 7, net),
                                         {e1, e2})
            hits += found and not spurious
        rows.append((e1, e2, 100.0 * hits / sets))
        progress(f"{e1} + {e2}: {rows[-1][2]:.0f} %")
    return rows


def _option(name, default, kind=int):
    return kind(sys.argv[sys.argv.index(name) + 1]) if name in sys.argv else default


def main():
    """Run the study the options name (module docstring) and print its table."""
    if "--mems" in sys.argv:
        print(f"MEMS-size units, two-axis stand, 30 x 45 degree grid, sigma = {SIGMA:g}, "
              "g exact (--g), mounting to 5e-3 rad, stand errors to 2e-5 rad")
        print("  set  verdict     largest guaranteed error  largest |q - q_true| / bound")
        for k, (ok, worst, ratio) in enumerate(mems_sets()):
            verdict = f"{Status.CONSISTENT:10s}  {worst:24.2e}  {ratio:.4f}" if ok else str(Status.REFUTED)
            print(f"  {k:3d}  {verdict}")
        return 0
    if "--mems-stands" in sys.argv:
        sets = _option("--sets", 20)
        print(f"MEMS-size blocks (scale errors to 2e-2, misalignments to 1e-2 rad, biases to 0.1 g), stand, mounting "
              f"and Delta_g/g within their stated bounds, {sets} sets per stand (half at the box's vertices), noise "
              f"at +-sigma = {SIGMA:g}, then at the largest bound's estimator's own signs; a local --g")
        for name in MEMS_STANDS:
            runs, ok, out, ratios = mems_sweep(name, sets)
            print(f"  {name:12s} {runs} runs, {ok} consistent, {out} truths outside a printed bound (or a printed "
                  f"bound "
                  f"above the a-priori one); each q's a-priori bound over its bound with block errors of 1e-4, largest "
                  f"per run: {min(ratios):.2f}-{max(ratios):.2f}x", flush=True)
        return 0
    if "--information" in sys.argv:
        sets = _option("--sets", 5)
        print(f"two-axis stand, small units (errors up to 1e-4), sigma = {SIGMA:g}, a local --g, {sets} sets per row: "
              "the printed bound (what the readings prove) over the a-priori one (what the plan guarantees), median "
              "over sets and q; the median printed bound in sigma; truths outside a printed bound")
        print("  positions                     noise     proven / a priori  bound (sigma)  outside")
        for label, noise, ratio, bound, outside, runs in information(sets):
            print(f"  {label:28s}  {noise:8s}  {ratio:17.2f}  {bound:13.2f}  {outside} of {runs}", flush=True)
        return 0
    if "--clean" in sys.argv:
        n = _option("--clean", 200)
        print(f"false alarms of diagnose on {n} clean sets (two-axis, 96 positions, small and MEMS-size units, "
              f"uniform and clipped noise, sigma = {SIGMA:g}): {clean_alarms(n)}")
        return 0
    sets = _option("--sets", 20)
    net = "--net" in sys.argv
    if "--pairs" in sys.argv:
        print(f"two effects at 2 sigma each{' (the part the model cannot absorb)' if net else ''}, two-axis 96 "
              f"positions, {sets} sets per pair (small and MEMS-size, uniform and clipped noise): % of sets with "
              "exactly those two named", flush=True)
        pairs(sets, progress=lambda text: print(text, flush=True), net=net)
        return 0
    levels = tuple(float(x) for x in _option("--levels", "1,1.5,2,3", str).split(","))
    print(f"% of {sets} sets in which diagnose names the hidden effect (random direction, shuffled positions, "
          f"half uniform and half clipped-Gaussian noise), sigma = {SIGMA:g}; and % with a spurious effect", flush=True)
    setups = [tuple(x.split(":", 1)) for x in _option("--setup", "", str).split(",") if x] or SETUPS
    sizes = tuple(_option("--units", ",".join(SIZES), str).split(","))
    if net:
        print("level: the part of the effect's change the current model cannot absorb (its minimax residual "
              "after the best q), in sigma", flush=True)
    print("stand  plan  unit  effect  level  named %  spurious %  refuted %", flush=True)
    rates(sets, levels, setups, progress=lambda text: print(text, flush=True), net=net, sizes=sizes)
    return 0

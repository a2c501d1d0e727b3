"""garant simulate: readings from the exact nonlinear model, with hidden effects, for testing."""
from ..outcomes import Exit
from . import flags


def add(sub):
    """The `garant simulate` subcommand and its flags."""
    p = sub.add_parser("simulate", help="readings from the exact model with hidden effects (for testing)")
    flags.model(p)
    p.add_argument("--plan", required=True, help="optimal10, quarter16, grid:AxB (steps per angle in degrees), or a "
                   "plan file PLAN.csv (`garant plan -o`); --model norm: random:N, faces or optimal (001's 18)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME=v1,v2,...",
                   help="a catalogue effect and its parameter values (repeatable)")
    flags.sigma(p, "noise bound, units of g")
    p.add_argument("--seed", type=flags.seed, default=0, help="random seed, a whole number >= 0 (default 0)")
    flags.g(p)
    p.add_argument("--size", metavar="B|KIND=B,...",
                   help="bound of the random errors: one for all (default 1e-4), or per kind, e.g. "
                        "stand=1e-4,mounting=3e-3,block=1e-2,bias=0.05 (kinds not named: 0; a bias over g)")
    p.add_argument("--truth", metavar="FILE.json",
                   help='the stand\'s errors by name instead of random ones, e.g. {"kappa": 5e-5, "Gamma11": 1.2e-2, '
                        '"bias1": 0.05} (rad, dimensionless, a bias over g); the others 0')
    p.add_argument("--temperatures", type=flags.temperatures, metavar="T1,T2,...",
                   help="chamber temperatures (C): the plan at each, temp_c set to it; --truth may then name thermal "
                        "coefficients p_Tk of a block parameter p (e.g. bias1_T1, Gamma11_T2: per C^k about the middle "
                        "of the temperatures)")
    p.add_argument("--temperature-profile", metavar="PROFILE",
                   help="--model norm: each sample's temperature, warmup:T0,T1,TAU (from T0 towards T1 C, time "
                        "constant TAU s) or cycle:T0,T1,PERIOD (T0 to T1 and back, s); a temp_c column")
    p.add_argument("--ordered", action="store_true",
                   help="--model norm: visit the orientations in order, face up first and face down last (as a board "
                        "is turned over by hand), not shuffled")
    p.add_argument("--revisit", type=flags.count, default=0, metavar="N",
                   help="--model norm: at the end, turn back through the first N orientations in reverse order (hot, "
                        "on a warm-up)")
    p.add_argument("--still", type=flags.positive, default=8.0, metavar="S",
                   help="--model norm: seconds each orientation is held still (default 8)")
    p.add_argument("--move", type=flags.positive, default=2.0, metavar="S",
                   help="--model norm: seconds of each move between orientations (default 2)")
    p.add_argument("--rate", type=flags.rate, default=100.0, metavar="HZ",
                   help="--model norm: samples per second (default 100)")
    p.add_argument("-o", "--output", required=True, metavar="DATA.csv")
    return p


def run_norm(args):
    """`garant simulate --model norm`: the log of a unit turned by hand (workflows/simulate_log.py) and its truth."""
    from .. import models
    from ..errors import DataError
    from ..io import report
    from ..workflows import simulate_log
    if args.truth or args.temperatures:
        raise DataError("--model norm: a unit turned by hand draws its errors within --size and takes a temperature "
                        "profile (--temperature-profile warmup:T0,T1,TAU), not --truth or --temperatures",
                        param="model")
    try:
        size = float(args.size or "1e-3")
    except ValueError:
        raise DataError(f"--size {args.size[:40]!r}: --model norm takes one bound for every error (scale, "
                        "misalignment in rad, bias over g)", param="size") from None
    if not 0 <= size <= 0.2:
        raise DataError(f"--size {size:g}: a bound from 0 to 0.2", param="size")
    effects = simulate_log.parse_effects(args.effect, models.load("norm"))
    t, raw, T, truth = simulate_log.simulate(args.plan, effects, args.sigma, args.seed, args.g, size,
                                             args.temperature_profile, args.ordered, args.still, args.move, args.rate,
                                             args.revisit)
    path = truth_path(args.output)
    report.check_writable(path, "the truth file")
    simulate_log.write(args.output, t, raw, T)
    hidden = ", ".join(f"{n}={','.join(f'{v:g}' for v in vals)}" for n, vals in effects.items()) or "none"
    print(f"wrote {args.output}: {len(t)} samples (m/s^2) over {t[-1]:.1f} s, {truth['orientations']} still "
          f"orientations of {args.still:g} s ({'in order, face up first' if args.ordered else 'shuffled'}), noise "
          "within "
          f"+-{args.sigma:g} g per sample, effects: {hidden}"
          + ("" if T is None else f"; temperature {T.min():.1f} to {T.max():.1f} C (temp_c)"))
    report.write_json(path, {"model": "norm", **truth})
    print(f"wrote {path}: the hidden truth (the block's errors, M and b, the effects in the convention calibrate-norm "
          "prints them in)")
    return Exit.OK



def run(args):
    """`garant simulate`: parse, call the job, print; the exit status."""
    import numpy as np

    from garant.derive.effects import CATALOGUE

    from .. import models
    from ..errors import DataError
    from ..io import report
    from ..workflows import simulate
    if models.kind(args.model) == "norm":
        return run_norm(args)
    for name in ("temperature_profile", "ordered", "revisit"):
        if getattr(args, name):
            raise DataError(f"--{name.replace('_', '-')} is for a unit turned by hand (--model norm); a stand takes "
                            "--temperatures",
                            param=name)
    base = models.stand_model(args.model)
    mod = models.load(args.model)
    effects = [simulate.parse_effect(e, CATALOGUE, [a.name for a in base.stand.angles]) for e in args.effect]
    if args.truth and args.size:
        raise DataError("--truth sets every error of the stand; --size draws them at random: give one", param="truth")
    given = simulate.read_truth(args.truth, mod, thermal=args.temperatures is not None) if args.truth else None
    sizes = simulate.parse_sizes(args.size or "1e-4")
    P, f, t, T, values, mounts = simulate.simulate(base, mod, args.plan, effects, args.sigma, args.seed, args.g,
                                                   sizes, given, args.temperatures)
    names, mount_names = models.layout(mod)
    if not np.all(np.isfinite(f)):
        raise DataError("the simulated readings are not finite (an effect or option too large); nothing written",
                        param="effect")
    truth = truth_path(args.output)
    units = {p.name: p.unit for p in base.parameters}
    report.check_writable(truth, "the truth file")
    simulate.write(args.output, P, f, t, T, names, mounts, mount_names)
    hidden = ", ".join(f"{n}={','.join(f'{v:g}' for v in vals)}" for n, vals in effects) or "none"
    print(f"wrote {args.output}: {len(P)} positions, noise within +-{args.sigma:g} g, effects: {hidden}"
          + (f"; at {', '.join(f'{t:g}' for t in args.temperatures)} C" if args.temperatures else ""))
    report.write_json(truth, {"model": args.model, "plan": args.plan, "sigma": args.sigma, "g": args.g,
                              "seed": args.seed, "effects": {n: list(v) for n, v in effects},
                              "drawn": ({"from": args.truth} if given is not None else
                                        {"uniform_within": sizes, "seed": args.seed}),
                              "parameters": {n: float(v) for n, v in values.items()},
                              "units": {n: units.get(n, "see the effect catalogue") for n in values},
                              "q": dict(zip(mod.Q_NAMES, models.q_of(mod, [values.get(n, 0.0) for n in
                                                                             mod.PARAMETER_NAMES]).tolist())),
                              "q_absorbs": list(mod.ABSORBED),
                              "temperatures_c": args.temperatures})
    print(f"wrote {truth}: the hidden truth (parameters, q, effects)")
    return Exit.OK


def truth_path(output):
    """DATA.csv -> DATA.truth.json, beside the data."""
    return str(output)[:-4] + ".truth.json" if str(output).endswith(".csv") else str(output) + ".truth.json"

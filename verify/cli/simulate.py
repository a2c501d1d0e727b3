"""garant simulate: readings from the exact nonlinear model, with hidden effects, for testing."""
from . import args as a


def add(sub):
    p = sub.add_parser("simulate", help="readings from the exact model with hidden effects (for testing)")
    a.model(p)
    p.add_argument("--plan", required=True, help="optimal10, quarter16 or grid:AxB (alpha, beta steps in degrees)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME=v1,v2,...",
                   help="a catalogue effect and its parameter values (repeatable)")
    a.sigma(p, "noise bound, units of g")
    p.add_argument("--seed", type=int, default=0)
    a.g(p)
    p.add_argument("--size", type=a.positive, default=1e-4, help="bound of the random stand and block errors")
    p.add_argument("-o", "--output", required=True, metavar="DATA.csv")
    return p


def run(args):
    from garant.derive.effects import CATALOGUE

    from .. import models
    from ..workflows import simulate
    base = models.stand_model(args.model)
    mod = models.load(args.model)
    effects = [simulate.parse_effect(e, CATALOGUE) for e in args.effect]
    P, f, t, T, _, mounts = simulate.simulate(base, mod, args.plan, effects, args.sigma, args.seed, args.g,
                                              args.size)
    names, mount_names = models.layout(mod)
    simulate.write(args.output, P, f, t, T, names, mounts, mount_names)
    hidden = ", ".join(f"{n}={','.join(f'{v:g}' for v in vals)}" for n, vals in effects) or "none"
    print(f"wrote {args.output}: {len(P)} positions, noise within +-{args.sigma:g} g, effects: {hidden}")
    return 0

"""Strong and weak scaling of one run on up to 8 GPUs, modelled from parts this project measures
(issue 69; docs/results/ranks.md). No GPU ran this: every GPU figure it prints is the model's,
from the rate and the bandwidths it is given, which are stated assumptions.

    python bench/ranks_model.py [--scene dambreak1_lab] [--dx 0.002] [--rates 20 100 500]
        [--link nvlink|pcie|infiniband] [--ranks 1 2 4 8] [--weak-particles 3e6]

The measured parts, from ``gpusph-plan --ranks N`` (plan.rank_plan: the cut the run makes, each
rank's particles and its 3-cell halo, counted from the scene's build):
- each rank's owned particles and halo particles, the slowest rank's setting the step;
- the bytes each rank's halo refresh moves a step (decomposition.exchange_bytes).

The model of one step on rank r (a GPU steps its halo with its own particles, sph/exchange.py):

    t_r = (N_r + H_r) / R  +  B_r / link  +  staged * B_r / pcie  +  messages * latency

R the device's rate [particle-steps/s], B_r the halo's bytes a step, ``link`` the bandwidth
between GPUs, ``staged`` 2 where the halo goes through pinned host memory (the pip MPI wheels are
not CUDA-aware: device to host, then host to device) and 0 over NVLink peer copies, and
``messages`` the exchanges a step waits on (the halo from each side; the all-reduces of the step's
maxima, the lists' staleness and the stop flag; the all-gather of the health checks). The run's
step is the slowest rank's; one GPU's is N / R. Strong scaling: the same run on P GPUs. Weak: P
times the particles on P GPUs (dx shrunk by P^(1/3)).
"""
import argparse

# stated assumptions, per direction, sustained [B/s] and per message [s]
LINKS = {"nvlink": (300e9, 0, 5e-6), "pcie": (25e9, 2, 10e-6), "infiniband": (25e9, 2, 5e-6)}
PCIE = 25e9  # a PCIe 4.0 x16 link's sustained bytes a second, one direction
MESSAGES = 6  # the exchanges a step waits on (sph/exchange.py): 2 halo sides, 3 all-reduces, 1 all-gather


def model(plan: dict, rate: float, link: str, host_s: float = 0.0) -> float:
    """The modelled seconds a step on the plan's ranks at ``rate`` over ``link``; ``host_s``: the
    exchange as built today instead, that many seconds a particle a rank holds (its arrays copied
    through the host each step: bench/ranks.py measures it)."""
    bandwidth, staged, latency = LINKS[link]
    worst = 0.0
    for own, halo, bytes_ in zip(plan["particles"], plan["halo"], plan["exchange_bytes"]):
        exchange = bytes_ / bandwidth + staged * bytes_ / PCIE + MESSAGES * latency + host_s * (own + halo)
        worst = max(worst, (own + halo) / rate + (exchange if plan["ranks"] > 1 else 0.0))
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="dambreak1_lab")
    ap.add_argument("--dx", type=float, default=0.002)
    ap.add_argument("--rates", type=float, nargs="+", default=[20.0, 100.0, 500.0], help="MIPPS a GPU (assumed)")
    ap.add_argument("--link", nargs="+", default=list(LINKS), choices=list(LINKS))
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 4, 6, 8])
    ap.add_argument("--host-us", type=float, default=0.0,
                    help="also the exchange as built today: microseconds a held particle a step (bench/ranks.py's "
                         "exchange time a step over the particles a rank holds)")
    args = ap.parse_args()
    from gpusph_ros.plan import rank_plan
    from gpusph_ros.scenes.schema import load_scene
    from gpusph_ros.scenes.settings import resolve

    scene = load_scene(args.scene)

    def plan(dx: float, ranks: int) -> dict:
        return rank_plan(scene, resolve(scene, dx=dx, device="cpu"), ranks)

    strong = {p: plan(args.dx, p) for p in args.ranks}
    weak = {p: plan(args.dx / p ** (1.0 / scene.dim), p) for p in args.ranks}
    for name, plans in (("strong", strong), ("weak", weak)):
        print(f"{name} scaling, {args.scene} at dx = {args.dx:g} m" + (" / P^(1/3)" if name == "weak" else ""))
        for p, r in plans.items():
            total, halo = sum(r["particles"]), sum(r["halo"])
            print(f"  P = {p}: {total:,} particles, halo {halo / total:.1%} of them, slowest rank "
                  f"{max(o + h for o, h in zip(r['particles'], r['halo'])):,} held, "
                  f"{max(r['exchange_bytes']) / 2 ** 20:.3g} MiB a step")
        ways = [(link, 0.0) for link in args.link] + [("pcie", args.host_us * 1e-6)] * bool(args.host_us)
        for link, host_s in ways:
            for rate in args.rates:
                one = model(plans[args.ranks[0]], rate * 1e6, link)
                cells = []
                for p, r in plans.items():
                    t = model(r, rate * 1e6, link, host_s)
                    # strong: the speed-up; weak: the particle-steps a second against one GPU's
                    cells.append(f"P={p}: {one / t * (1 if name == 'strong' else p / args.ranks[0]):.2f}x")
                label = "as built" if host_s else link
                print(f"  {label:10s} {rate:5g} MIPPS a GPU: " + ", ".join(cells))


if __name__ == "__main__":
    main()

"""The bench's section ``peers``: chainrun against the peers on the paper's Hertz line.

Hertz line, K = 1, until t = 1.25 N + 20 (the wave has left the far end): chainrun as
a whole process and in-process, and each available peer of ``benchmarks.peers``; the
errors of the final velocities against chainrun at ``REFERENCE_RTOL`` to the same
time, and the agreement of every pair of tools within their claimed accuracies
(``ACCURACY``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmarks.harness import (ACCURACY, REFERENCE_RTOL, SHORT, Context, chainrun_point,
                                config_text, fmt_e, fmt_t, log, max_error, predict,
                                solve_paper, table)
from benchmarks.peers import PeerResult, PeerUnavailable
from benchmarks.sections import Result


@dataclass
class PeersResult(Result):
    """One case per N: its reference, and each tool's run (``tools``, dicts with the
    tool's name, time, steps, events, error against the reference) and agreement."""

    cases: list = field(default_factory=list)

    def lines(self) -> list[str]:
        out = ["Peers' case: Hertz line, K = 1, until t = 1.25 N + 20; error = max |v - v_ref| "
               f"of the final velocities, v_ref from chainrun at rtol = {REFERENCE_RTOL:g}"]
        rows = []
        for case in self.cases:
            cr = next(t for t in case["tools"] if t["tool"] == "chainrun")
            proc_t, solv_t = cr.get("process_time"), cr.get("time")
            rows.append([str(case["n"]), "chainrun process", fmt_t(proc_t), "1", "-",
                         str(cr.get("events", "-")), str(cr.get("steps", "-")),
                         fmt_e(cr.get("error_vs_reference")), ""])
            rows.append(["", "chainrun solver", fmt_t(solv_t), "-", "1", "", "", "", ""])
            for t in case["tools"]:
                if t["tool"] in ("chainrun", "chainrun-cli"):
                    continue
                if t.get("time") is None:
                    rows.append(["", t["tool"], "-", "", "", "", "", "",
                                 t.get("skipped") or t.get("error", "")])
                    continue
                e = t.get("error_vs_reference")
                flag = " !" if e is not None and e > ACCURACY[t["tool"]] else ""
                rows.append(["", t["tool"], fmt_t(t["time"]),
                             f"{t['time'] / proc_t:.3g}" if proc_t else "-",
                             f"{t['time'] / solv_t:.3g}" if solv_t else "-",
                             str(t["events"]), str(t["steps"]), fmt_e(e) + flag,
                             f"+{fmt_t(t['compile_time'])} s compile" if t["tool"] == "heyoka"
                             else ""])
        out.append(table(["N", "tool", "time s", "x proc", "x solver", "events", "steps",
                          "error", "note"], rows, "llrrrrrrl"))
        out.append("")
        out.append("Agreement (pairwise max |v_a - v_b| within the sum of claimed accuracies "
                   + ", ".join(f"{k} {v:g}" for k, v in ACCURACY.items() if k != "chainrun-cli")
                   + "):")
        for case in self.cases:
            ag = case["agreement"]
            bad = [f"{q['a']}~{q['b']} {q['max_diff']:.1e} > {q['allowed']:.0e}"
                   for q in ag["pairs"] if not q["ok"]]
            bad += [f"{o['tool']} error {o['error']:.1e} > claimed {o['claimed']:.0e}"
                    for o in ag["off"]]
            worst = max(ag["pairs"], key=lambda q: q["max_diff"] / q["allowed"], default=None)
            line = f"  N = {case['n']}: " + ("all agree" if ag["ok"]
                                             else "DISAGREE: " + "; ".join(bad))
            if worst and ag["ok"]:
                line += (f" (closest to its bound: {worst['a']}~{worst['b']} "
                         f"{worst['max_diff']:.1e} <= {worst['allowed']:.0e})")
            out.append(line)
        return out

    def largest(self) -> dict | None:
        """The case of the largest N, with its tools by name: what the README quotes."""
        if not self.cases:
            return None
        case = max(self.cases, key=lambda c: c["n"])
        return dict(case, tools={t["tool"]: t for t in case["tools"]})


RESULT = PeersResult


def peer_runners(mode, notes: list[str]) -> dict:
    """The available peers: name -> solve(n, k, alpha, t_stop)."""
    from benchmarks.peers import heyoka_peer, rk4_paper, scipy_dop853

    runners = {"scipy": scipy_dop853.solve, "rk4": rk4_paper.solve}
    ok, why = heyoka_peer.available()
    if ok:
        runners["heyoka"] = heyoka_peer.solve
    else:
        notes.append(f"heyoka skipped: {why}")
        log(f"  heyoka skipped: {why}")
    return runners


def run_peer(name, solve, n, k, alpha, t_stop) -> dict:
    """One peer run, repeated when short; the fastest solve, compilation apart."""
    runs: list[PeerResult] = []
    try:
        while True:
            runs.append(solve(n, k, alpha, t_stop))
            best = min(runs, key=lambda r: r.solve_time)
            limit = 5 if best.solve_time < SHORT / 10 else 3
            if best.solve_time >= SHORT or len(runs) >= limit:
                break
    except PeerUnavailable as exc:
        return {"tool": name, "n": n, "error": str(exc)}
    except Exception as exc:                       # a peer failing is a result too
        return {"tool": name, "n": n, "error": f"{type(exc).__name__}: {exc}"}
    return {"tool": name, "n": n, "time": best.solve_time,
            "times": [r.solve_time for r in runs], "compile_time": runs[0].compile_time,
            "steps": best.steps, "events": best.events, "settings": best.settings,
            "final_velocity": best.final_velocity}


def agreement(tools: list[dict]) -> dict:
    """Pairwise max differences of the final velocities, checked against the tools'
    claimed accuracies (``ACCURACY``): a pair disagrees when its difference exceeds
    the sum of the two; a tool is off when its error exceeds its own claim."""
    have = [t for t in tools if "final_velocity" in t]
    pairs = []
    for i, a in enumerate(have):
        for b in have[i + 1:]:
            diff = max_error(a["final_velocity"], b["final_velocity"])
            allowed = ACCURACY[a["tool"]] + ACCURACY[b["tool"]]
            pairs.append({"a": a["tool"], "b": b["tool"], "max_diff": diff,
                          "allowed": allowed, "ok": diff <= allowed})
    off = [{"tool": t["tool"], "error": t["error_vs_reference"],
            "claimed": ACCURACY[t["tool"]]}
           for t in have if t.get("error_vs_reference", 0.0) > ACCURACY[t["tool"]]]
    return {"pairs": pairs, "off": off, "ok": all(p["ok"] for p in pairs) and not off}


def run(ctx: Context) -> PeersResult:
    """The peers' case: Hertz, K = 1, until t = 1.25 N + 20."""
    mode, procs = ctx.mode, ctx.procs
    runners = peer_runners(mode, ctx.notes)
    rows = []
    history: dict[str, list] = {name: [] for name in runners}
    for n in mode.peers_n:
        t_stop = 1.25 * n + 20
        log(f"peers: N = {n}, t = {t_stop:g}")
        ref = solve_paper(n, 1, 1.5, t_end=t_stop, rtol=REFERENCE_RTOL)
        v_ref = ref.final_velocity
        case = {"n": n, "t_stop": t_stop, "reference_end_time": ref.end_time,
                "reference_outcome": ref.outcome.value, "tools": []}
        point = chainrun_point(n, 1, 1.5, t_end=t_stop)
        point["tool"] = "chainrun"
        proc, walls = procs.timed(config_text(f"peers-n{n}", n, 1, 1.5, t_end=t_stop))
        point.update(process_time=proc.wall, process_times=walls, process_cpu=proc.cpu,
                     process_maxrss_mb=proc.maxrss_mb, process_error=proc.error)
        case["tools"].append(point)
        if proc.final_velocity is not None:
            case["tools"].append({"tool": "chainrun-cli", "n": n,
                                  "final_velocity": proc.final_velocity})
        log(f"  chainrun: process {fmt_t(proc.wall)} s, solver {fmt_t(point['time'])} s, "
            f"error {fmt_e(max_error(point['final_velocity'], v_ref))}")
        for name, solve in runners.items():
            if name == "scipy" and n > mode.scipy_max_n:
                case["tools"].append({"tool": name, "n": n,
                                      "skipped": f"N > {mode.scipy_max_n} (--full for more)"})
                continue
            if history[name] and predict(history[name], n) > mode.peers_cap:
                case["tools"].append({"tool": name, "n": n, "skipped":
                                      f"predicted {fmt_t(predict(history[name], n))} s "
                                      f"(--full for more)"})
                continue
            r = run_peer(name, solve, n, 1, 1.5, t_stop)
            case["tools"].append(r)
            if r.get("time") is not None:
                history[name].append((n, r["time"]))
            log(f"  {name}: {fmt_t(r.get('time'))} s"
                + (f" (+{fmt_t(r['compile_time'])} s compile)" if r.get("compile_time") else "")
                + (f", error {fmt_e(max_error(r['final_velocity'], v_ref))}"
                   if "final_velocity" in r else f" {r.get('error', '')}"))
        for r in case["tools"]:
            if "final_velocity" in r:
                r["error_vs_reference"] = max_error(r["final_velocity"], v_ref)
        case["agreement"] = agreement(case["tools"])
        rows.append(case)
    return PeersResult(cases=rows)

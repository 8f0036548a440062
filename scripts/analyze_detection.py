#!/usr/bin/env python3
"""Explains the errors of a pcl_movers_detect run against objects.txt (diagnostic aid).

Usage: analyze_detection.py OBJECTS_TXT TRACKS_CSV [--sector-deg 180] [--verbose]

Classifies every false alarm (mover row in the sector inside no target's grown box) by what it
lies on (a non-moving labelled object or nothing labelled), range, track age, speed and cluster
size, and every missed visible target frame by its cause: no row near the target (no cluster or
merged into a large one), a row that is not yet confirmed (young track), a row whose speed is below
the mover threshold, or a confirmed-speed row still not declared a mover. Same hit/visibility rules
as pcl_movers_eval (>= 10 points, box grown by 1 m in length and width, sensor-frame centroid).
"""
import argparse
import collections
import csv
import math


def load_objects(path):
    objs = collections.defaultdict(list)
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            t = line.split()
            o = dict(frame=int(t[0]), id=int(t[1]), cls=t[2], cx=float(t[3]), cy=float(t[4]),
                     cz=float(t[5]), l=float(t[6]), w=float(t[7]), h=float(t[8]), yaw=float(t[9]),
                     moving=int(t[10]), speed=float(t[11]), n=int(t[12]))
            objs[o["frame"]].append(o)
    return objs


def inside(o, x, y, grow=1.0):
    dx, dy = x - o["cx"], y - o["cy"]
    c, s = math.cos(o["yaw"]), math.sin(o["yaw"])
    u, v = c * dx + s * dy, -s * dx + c * dy
    return abs(u) <= (o["l"] + grow) / 2 and abs(v) <= (o["w"] + grow) / 2


def in_sector(x, y, deg):
    return deg >= 180 or abs(math.degrees(math.atan2(y, x))) <= deg


def bucket(v, edges):
    for e in edges:
        if v < e:
            return f"<{e}"
    return f">={edges[-1]}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("objects")
    ap.add_argument("tracks")
    ap.add_argument("--sector-deg", type=float, default=180)
    ap.add_argument("--verbose", action="store_true")
    a = ap.parse_args()
    objs = load_objects(a.objects)
    rows = collections.defaultdict(list)
    first_seen = {}
    with open(a.tracks) as f:
        for r in csv.DictReader(f):
            r = {k: (float(v) if k not in ("frame", "track_id", "mover", "points") else int(v))
                 for k, v in r.items()}
            rows[r["frame"]].append(r)
            first_seen.setdefault(r["track_id"], r["frame"])
    frames = sorted(set(objs) | set(rows))
    fa = collections.Counter()
    fa_detail = []
    miss = collections.Counter()
    miss_by_target = collections.defaultdict(collections.Counter)
    for fr in frames:
        os_ = objs.get(fr, [])
        targets = [o for o in os_ if o["moving"]]
        for r in rows.get(fr, []):
            if not r["mover"] or not in_sector(r["x"], r["y"], a.sector_deg):
                continue
            if any(inside(o, r["x"], r["y"]) for o in targets):
                continue
            on = [o for o in os_ if inside(o, r["x"], r["y"])]
            rng = math.hypot(r["x"], r["y"])
            kind = f"static {on[0]['cls']}" if on else "unlabelled"
            age = fr - first_seen[r["track_id"]]
            fa[(kind, bucket(rng, [15, 30, 45, 60]))] += 1
            fa_detail.append((fr, r["track_id"], kind, rng, age, r["speed"], r["points"], r["length"],
                              r["height"], r["similarity"]))
        for o in targets:
            if o["n"] < 10 or not in_sector(o["cx"], o["cy"], a.sector_deg):
                continue
            near = [r for r in rows.get(fr, []) if inside(o, r["x"], r["y"])]
            if any(r["mover"] for r in near):
                continue
            if not near:
                # A row whose box would cover the target (merged into something large)?
                big = [r for r in rows.get(fr, []) if math.hypot(r["x"] - o["cx"], r["y"] - o["cy"])
                       < 0.5 * r["length"] + 1]
                why = "merged/large cluster" if big else "no cluster"
            else:
                r = max(near, key=lambda r: r["points"])
                age = fr - first_seen[r["track_id"]]
                if age < 4:
                    why = "young track (<4 frames)"
                elif r["speed"] < 1.2:
                    why = "speed below threshold"
                else:
                    why = "fast but not confirmed"
            miss[why] += 1
            miss_by_target[(o["id"], o["cls"])][why] += 1
    print(f"false alarms: {sum(fa.values())}")
    for k, v in sorted(fa.items(), key=lambda kv: -kv[1]):
        print(f"  {v:4d}  {k[0]:18s} range {k[1]}")
    if a.verbose:
        print("  frame track kind range age speed points length height B")
        for d in fa_detail:
            print("  %4d %5d %-16s %5.1f %3d %5.2f %5d %5.2f %4.2f %4.2f" % d)
    per_track = collections.Counter((d[1], d[2]) for d in fa_detail)
    print(f"  distinct tracks: {len(per_track)}; top: " +
          ", ".join(f"#{k[0]} {k[1]} x{v}" for k, v in per_track.most_common(8)))
    print(f"missed target frames: {sum(miss.values())}")
    for k, v in miss.most_common():
        print(f"  {v:4d}  {k}")
    for (tid, cls), c in sorted(miss_by_target.items()):
        print(f"  target {tid} {cls}: " + ", ".join(f"{k} {v}" for k, v in c.most_common()))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Compares the four far-study CSVs of ab_far_study.sh (OUT/A1, B1, B2, A2.csv).

Every count (answers, PCS sizes, pairs tested, queries, draws) must be the same in all four
runs: a difference is printed and the exit status is 1. Step times: per row (scene,
configuration, output, distance) the ratio of B's mean median to A's, summarized over all rows
and per scene, beside the A2/A1 and B2/B1 ratios that show the machine's own spread.
Usage: ab_far_study_compare.py OUT
"""
import csv
import statistics
import sys

COUNTS = ['pcs_objects', 'pcs_primitives', 'object_pairs', 'pairs_considered', 'pairs_tested',
          'subobject_input', 'contacts_total', 'reference_total', 'missed_total',
          'false_positives_total', 'distance_pairs_total', 'distance_reference_total',
          'distance_missed_total', 'distance_spurious_total', 'queries', 'draws',
          'primitives_rendered', 'object_pairs_total']


def load(path):
    with open(path, newline='') as f:
        return {(r['scene'], r['config'], r['output'], r['distance']): r
                for r in csv.DictReader(f)}


def spread(ratios):
    q = statistics.quantiles(ratios, n=4)
    return (f'median {statistics.median(ratios):.3f} (p25 {q[0]:.3f}, p75 {q[2]:.3f}, '
            f'min {min(ratios):.3f}, max {max(ratios):.3f})')


def main(out):
    runs = {name: load(f'{out}/{name}.csv') for name in ('A1', 'B1', 'B2', 'A2')}
    keys = [k for k in runs['A1'] if all(k in rows for rows in runs.values())]
    differences = 0
    for key in keys:
        for column in COUNTS:
            values = {name: rows[key].get(column) for name, rows in runs.items()}
            if len(set(values.values())) > 1:
                differences += 1
                print('count differs:', key, column, values)
    print(f'rows {len(keys)}, count differences: {differences}')
    ms = {name: {k: float(rows[k]['step_ms_median']) for k in keys} for name, rows in runs.items()}
    ratios, by_scene = [], {}
    for k in keys:
        a = (ms['A1'][k] + ms['A2'][k]) / 2
        b = (ms['B1'][k] + ms['B2'][k]) / 2
        if a > 0:
            ratios.append(b / a)
            by_scene.setdefault(k[0], []).append(b / a)
    print('B/A:', spread(ratios))
    for scene, scene_ratios in by_scene.items():
        print(f'  {scene} ({len(scene_ratios)} rows): median {statistics.median(scene_ratios):.3f}')
    for x, y in (('A1', 'A2'), ('B1', 'B2')):
        same = [ms[y][k] / ms[x][k] for k in keys if ms[x][k] > 0]
        print(f'{y}/{x}:', spread(same))
    return 1 if differences else 0


if __name__ == '__main__':
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1]))

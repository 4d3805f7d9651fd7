"""A study on a Dask cluster: one task per recording (pymodal.batch_row, the GIL released), the
rows gathered into one pandas DataFrame, the same table as pymodal.batch's.

Run:  python examples/batch_dask.py INPUTS... [--out DIR] [--workers 2] [--scheduler ADDRESS]

INPUTS are recordings, folders or glob patterns. Without --scheduler, a LocalCluster of
--workers processes is started (one thread each: a task is one recording on one core). Needs
`pip install 'pedomatch[dask]'` (dask[distributed] and pandas).
"""

import argparse

import pandas as pd
from distributed import Client, LocalCluster

import pymodal


def dask_study(client, inputs, out=None, figures="none", **options):
    """The study table of `inputs` computed on `client`'s workers, as a DataFrame in the order of
    pymodal.find_recordings (the order of pymodal.batch's rows). With `out`, every recording's
    folder is written there (the workers must see that folder)."""
    paths = pymodal.find_recordings(inputs)
    # pure=False: a recording is run even if an identical task ran before (its folder may be gone).
    futures = client.map(pymodal.batch_row, paths, out=out, figures=figures, pure=False, **options)
    return pd.DataFrame(client.gather(futures))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("--out", help="study folder (one folder per recording)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scheduler", help="address of a running scheduler (tcp://host:8786)")
    args = ap.parse_args()
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    with client:
        table = dask_study(client, args.inputs, out=args.out)
    print(table.drop(columns=["path"]).to_string())
    if args.out:
        table.to_csv(f"{args.out}/study.csv", index=False)
        print(f"study table in {args.out}/study.csv")


if __name__ == "__main__":
    main()

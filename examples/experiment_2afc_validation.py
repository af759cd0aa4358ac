"""The 2AFC visual validation experiment, end to end.

1. Pair each nmmm rendering with the photograph of the real plate it predicts and write a
   ``pairs.toml`` (here: synthetic stand-in images; replace the triples with your files).
2. Serve the experiment to participants (a browser on a calibrated display):

       nmmm experiment serve experiment_out/pairs/pairs.toml --db responses.sqlite

   The experimenter page (progress, resume links, CSV export) is printed at start-up.
3. Analyse:

       nmmm experiment stats responses.sqlite --plot 2afc.png --delta 0.1
       nmmm experiment export responses.sqlite -o responses.csv

Run this script to do 1 and, instead of real participants, 3 on 40 simulated observers.
"""

from pathlib import Path

from nmmm.experiment import analyse_responses, format_report, load_pairs, plot_analysis, read_responses
from nmmm.experiment.simulation import simulate_responses, synthetic_pairs

out = Path("experiment_out")
pairs_toml = synthetic_pairs(out / "pairs", n_pairs=10, repetitions=2, viewing_distance_cm=50)
# With real images:
#   from nmmm.experiment import make_pairs_file
#   make_pairs_file([("render/hematite5.png", "photos/hematite5.jpg", "hematite 5 %"), ...],
#                   out / "pairs.toml", repetitions=2)
pairset = load_pairs(pairs_toml)
print(f"{len(pairset)} pairs, {pairset.n_trials} trials per participant -> {pairs_toml}")

db = out / "simulated.sqlite"
for suffix in ("", "-wal", "-shm"):
    Path(f"{db}{suffix}").unlink(missing_ok=True)
simulate_responses(pairset, db, n_observers=40, mean_pc=0.55, rho=0.05, seed=7)
analysis = analyse_responses(read_responses(db), delta=0.1)
print(format_report(analysis))
plot_analysis(analysis, out / "experiment_2afc.png")
print(f"plot: {out / 'experiment_2afc.png'}")
print(f"try the participant page: nmmm experiment serve {pairs_toml} --db {out / 'responses.sqlite'}")

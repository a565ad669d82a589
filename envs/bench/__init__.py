"""Benchmarks, each one pipeline: measure → results file (JSON) → verdicts → rendered pages.
Measuring writes a results file with the machine, the versions and the command; rendering
turns it into Markdown and plots without measuring; each verdict against a target is one
small function of the results.

======================  ======================================================================
module                  what it holds
======================  ======================================================================
``throughput``          measure: the environments' speed against their peers, in one run
``workprecision``       measure: every integrator's cost against its error (against DOP853),
                        MuJoCo on the same scene, the environments' own error
``cost``                measure, part of ``workprecision``: the automatic substep counts
                        against the smallest fixed counts that meet the same tolerance
``mujoco_roller``       the roller scene built in MuJoCo, the peer of ``workprecision``
``timing``              best-of-repeats timing, interleaved, and the progress lines (stderr)
``records``             the results files (JSON) and the record of the machine
``verdicts``            the targets of both studies, one verdict function each
``markdown``            what the pages share: tables, dates, the machine and command section
``plots``               the plots of both pages
``report``              render ``docs/BENCHMARKS.md`` (work-precision)
``throughput_report``   render ``docs/THROUGHPUT.md``
``maintainers``         render ``docs/MAINTAINERS.md``: the targets and both studies' verdicts
======================  ======================================================================

``roller-gym benchmark`` runs the work-precision study (``--render``: the pages again from
``docs/benchmarks/workprecision.json``); ``python -m roller_gym.bench.throughput measure``
the throughput study (``render``: from ``docs/benchmarks/throughput.json``).
"""

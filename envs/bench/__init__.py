"""Benchmarks: measuring writes a results file (JSON, with the machine, the versions and the
command); rendering turns that file into Markdown and plots without measuring; each verdict
against a target is one small function of the results.

=================  ===========================================================================
module             what it holds
=================  ===========================================================================
``throughput``     the environments' speed against their peers, in ratios measured in one run
``workprecision``  the work-precision study: every integrator's cost against its error
                   (against DOP853), MuJoCo on the same scene, the environments' throughput
``mujoco_roller``  the roller scene built in MuJoCo, the peer of ``workprecision``
``cost``           part of ``workprecision``: the error-controlled integrators' substep counts
                   against the smallest fixed counts that meet the same tolerance, on hard steps
``report``         the work-precision results file, and its page and plots
``verdicts``       the work-precision targets, one verdict function each
=================  ===========================================================================

``roller-gym benchmark`` runs the work-precision study (``--render``: the page again from
``docs/benchmarks/workprecision.json``); ``python -m roller_gym.bench.throughput`` the
throughput study.
"""

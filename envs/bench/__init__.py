"""Benchmarks: measuring writes a results file (JSON, with the machine, the versions and the
command); rendering turns that file into Markdown without measuring.

=================  ===========================================================================
module             what it holds
=================  ===========================================================================
``throughput``     the environments' speed against their peers, in ratios measured in one run
=================  ===========================================================================

``roller-gym benchmark`` (``scripts/benchmark.py``) runs the work-precision study against
DOP853 and MuJoCo; ``python -m roller_gym.bench.throughput`` the throughput study.
"""

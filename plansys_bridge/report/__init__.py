"""Pictures and figures of a run: Gantt chart, plan graph, ``summary.json``.

:class:`~.model.RunReport` is built from what a
:class:`~plansys_bridge.monitoring.watch.MissionWatch` saw (a live run or a
recording, :mod:`.recording`); :func:`~.write.write_report` draws it into a folder.
"""

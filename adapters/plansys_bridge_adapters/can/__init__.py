"""CAN adapter: a differential-drive mobile base driven over python-can, described by a DBC.

Modules: ``dbc`` (the messages, typed, via cantools), ``bus`` (python-can bus, readers,
frame classification), ``monitor`` (what the base reports, why it cannot drive),
``controller`` (pure-pursuit path following with limits), ``performer``
(:class:`~.performer.CanBasePerformer`, the ``can`` performer kind), ``settings``
(its mission-file keys) and ``double`` (a simulated base on the same bus). Nothing
is imported here so that ``import plansys_bridge_adapters.can`` stays cheap.
"""

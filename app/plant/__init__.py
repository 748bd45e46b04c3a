"""Plant backends of the Motion-Lab scene: the lab's machines behind one interface.

``simulated`` (:class:`~app.plant.simulated.SimulatedLab`: the models of :mod:`app.sim`) or ``plc``
(:class:`~app.plant.plc.PlcLab`: the lab's TwinCAT PLC through the ADS bridge of :mod:`app.plc`).  The
scene (:class:`app.engine.lab_session.LabSession`) commands and reads a :class:`~app.plant.base.LabBackend`
and never knows which one it has.
"""

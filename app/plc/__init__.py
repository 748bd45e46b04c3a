"""The Motion-Lab's Beckhoff TwinCAT PLC over ADS: its symbol table and the ADS bridge thread.

:mod:`app.plc.symbols` holds what the lab's own HMI reads and writes (names, types, enums, rates);
:mod:`app.plc.bridge` runs one pyads connection in its own thread and hands everything it reads to the
engine through a queue (pyads is the optional extra ``bosun[plc]``, imported only when a bridge starts).
"""

"""PyQt5 + pyqtgraph operator HMI.  Talks to the engine only through the protocol."""

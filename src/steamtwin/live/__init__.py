"""The live twin: OPC UA in and out, sample by sample (issue 21).

``plant_server``: an OPC UA server (asyncua) that publishes a historian's tags live — the
virtual plant's, or any canonical SI frame with its tag map — for demos, tests and newcomers.
"""

#!/usr/bin/env python3
"""The cheapest possible protocol backend in Python: it claims the iQ-R conversions and answers
every case with "no change". What it measures is plc_adapter.py and the pipe, not a model."""

import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "adapters", "python"))

import plc_adapter  # noqa: E402

plc_adapter.serve(lambda case: None, name="trivial", version="1", profile="mitsubishi-iqr",
                  instructions=["HABIN", "HABINP", "DHABIN", "DHABINP",
                                "BINHA", "BINHAP", "DBINHA", "DBINHAP"])

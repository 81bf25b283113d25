"""What tests share: helper modules, and the scripts tests run as separate processes (ROS peers, lab programs).

:data:`REPO` is the repository's root; :data:`SUPPORT` this folder (scripts are run by path from it).
"""

from pathlib import Path

SUPPORT = Path(__file__).resolve().parent
REPO = SUPPORT.parents[1]

"""Studies built on the layers below: scenario files, the paper's reproduction, the
reconfigurable-arm demo, verification campaigns and the performance benchmark."""

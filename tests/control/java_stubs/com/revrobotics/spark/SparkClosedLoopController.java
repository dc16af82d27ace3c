// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.revrobotics.spark;
public class SparkClosedLoopController {
    public enum ArbFFUnits { kVoltage, kPercentOut }
    public Object setReference(double value, SparkBase.ControlType ctrl, ClosedLoopSlot slot, double arbFeedforward,
                               ArbFFUnits arbFFUnits) { return null; }
}

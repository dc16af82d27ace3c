// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.revrobotics.spark;
import com.revrobotics.spark.config.SparkBaseConfig;
public abstract class SparkBase {
    public enum ControlType { kDutyCycle, kVelocity, kVoltage, kPosition }
    public enum ResetMode { kResetSafeParameters, kNoResetSafeParameters }
    public enum PersistMode { kPersistParameters, kNoPersistParameters }
    public Object configure(SparkBaseConfig config, ResetMode resetMode, PersistMode persistMode) { return null; }
    public SparkClosedLoopController getClosedLoopController() { return new SparkClosedLoopController(); }
}

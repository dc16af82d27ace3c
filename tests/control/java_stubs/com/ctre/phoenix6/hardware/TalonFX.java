// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.ctre.phoenix6.hardware;
import com.ctre.phoenix6.configs.TalonFXConfigurator;
import com.ctre.phoenix6.controls.ControlRequest;
public class TalonFX {
    public TalonFXConfigurator getConfigurator() { return new TalonFXConfigurator(); }
    public Object setControl(ControlRequest request) { return null; }
}

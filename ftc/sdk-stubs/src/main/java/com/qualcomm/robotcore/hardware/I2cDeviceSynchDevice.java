// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

/**
 * Stub of the base class of user I2C drivers. The real class also re-initialises the device when the
 * hub is (re)armed; this stub only keeps the client and calls doInitialize() from initialize().
 */
public abstract class I2cDeviceSynchDevice<DEVICE_CLIENT extends I2cDeviceSynchSimple> implements HardwareDevice {
    protected DEVICE_CLIENT deviceClient;
    protected boolean deviceClientIsOwned;
    protected boolean isInitialized;

    protected I2cDeviceSynchDevice(DEVICE_CLIENT deviceClient, boolean deviceClientIsOwned) {
        this.deviceClient = deviceClient;
        this.deviceClientIsOwned = deviceClientIsOwned;
        this.isInitialized = false;
        deviceClient.enableWriteCoalescing(false);
    }

    protected void registerArmingStateCallback(boolean doInitialCallback) {
        if (doInitialCallback) {
            initialize();
        }
    }

    protected void engage() {
        if (deviceClient instanceof Engagable) {
            ((Engagable) deviceClient).engage();
        }
    }

    protected void disengage() {
        if (deviceClient instanceof Engagable) {
            ((Engagable) deviceClient).disengage();
        }
    }

    public DEVICE_CLIENT getDeviceClient() {
        return deviceClient;
    }

    public synchronized boolean initialize() {
        isInitialized = doInitialize();
        return isInitialized;
    }

    protected abstract boolean doInitialize();

    @Override
    public void resetDeviceConfigurationForOpMode() {
        deviceClient.resetDeviceConfigurationForOpMode();
        isInitialized = false;
    }

    @Override
    public void close() {
        if (deviceClientIsOwned) {
            deviceClient.close();
        }
    }

    @Override
    public int getVersion() {
        return 1;
    }

    @Override
    public String getConnectionInfo() {
        return deviceClient.getConnectionInfo();
    }
}
